// Decodes one CDR sample with its OMG IDL schema the way Foxglove does, with Foxglove's own
// modules (@foxglove/omgidl-parser, @foxglove/omgidl-serialization from the repository's
// js/node_modules, pinned there by scripts/install-deps.sh), and prints it as JSON.
//
//   node decode_cdr.mjs <schema name> <schema.idl> <sample.cdr>
//
// The schema name is the root type ("auv::msg::Odometry"); the sample starts with its
// encapsulation header. Output, one JSON document on stdout: structs as objects, sequences
// and arrays as arrays, 64-bit integers as exact JSON integers, enum values as the names of
// their enumerators (Foxglove shows those; a value the enum lacks stays a number),
// non-finite floats as the YAML spellings ".nan", ".inf", "-.inf". Exit status 1 with a
// message on stderr when the schema or the sample does not decode.
// AUV_JS_DIR overrides where the modules are looked for (default: <repo>/js).
import { readFileSync } from "node:fs";
import { dirname, resolve } from "node:path";
import { fileURLToPath } from "node:url";

import { cdrDecoder } from "./cdr_json.mjs";

const here = dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_JS_DIR || resolve(here, "../../../js");

if (process.argv.length !== 5) {
  process.stderr.write("usage: node decode_cdr.mjs <schema name> <schema.idl> <sample.cdr>\n");
  process.exit(2);
}
const [schemaName, idlPath, cdrPath] = process.argv.slice(2);

try {
  const decode = cdrDecoder(jsDir, schemaName, readFileSync(idlPath, "utf8"));
  process.stdout.write(decode(readFileSync(cdrPath)) + "\n");
} catch (error) {
  process.stderr.write(`decode_cdr: ${schemaName}: ${error.message ?? error}\n`);
  process.exit(1);
}
