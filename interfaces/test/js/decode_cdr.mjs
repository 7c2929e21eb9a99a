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
import { createRequire } from "node:module";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const jsDir = process.env.AUV_JS_DIR || resolve(here, "../../../js");
const require = createRequire(join(jsDir, "package.json"));
const { parseIDL } = require("@foxglove/omgidl-parser");
const { MessageReader } = require("@foxglove/omgidl-serialization");

if (process.argv.length !== 5) {
  process.stderr.write("usage: node decode_cdr.mjs <schema name> <schema.idl> <sample.cdr>\n");
  process.exit(2);
}
const [schemaName, idlPath, cdrPath] = process.argv.slice(2);

try {
  const definitions = parseIDL(readFileSync(idlPath, "utf8"));
  const byName = new Map(definitions.map((d) => [d.name, d]));
  const reader = new MessageReader(schemaName, definitions);
  const message = reader.readMessage(readFileSync(cdrPath));
  process.stdout.write(toJson(message, byName.get(schemaName), byName) + "\n");
} catch (error) {
  process.stderr.write(`decode_cdr: ${schemaName}: ${error.message ?? error}\n`);
  process.exit(1);
}

// Enumerator name of `value` in the enum called `enumType` (a module of constants).
function enumName(value, enumType, byName) {
  const constants = byName.get(enumType)?.definitions ?? [];
  const found = constants.find((c) => c.isConstant && c.value === value);
  return found ? found.name : value;
}

function scalar(value) {
  if (typeof value === "bigint") return value.toString();
  if (typeof value === "number") {
    if (Number.isNaN(value)) return '".nan"';
    if (!Number.isFinite(value)) return value > 0 ? '".inf"' : '"-.inf"';
    return Object.is(value, -0) ? "-0.0" : JSON.stringify(value);
  }
  return JSON.stringify(value);
}

// JSON of `value`, a field of type `field` (or the struct `definition` at the root).
function toJson(value, definition, byName, field) {
  if (Array.isArray(value) || ArrayBuffer.isView(value)) {
    const element = field ? { ...field, isArray: false, arrayLengths: undefined } : field;
    return "[" + Array.from(value, (v) => toJson(v, definition, byName, element)).join(",") + "]";
  }
  if (field && field.enumType && typeof value === "number") {
    return JSON.stringify(enumName(value, field.enumType, byName));
  }
  if (value !== null && typeof value === "object") {
    const struct = field ? byName.get(field.type) : definition;
    const members = struct?.definitions ?? [];
    const parts = Object.entries(value).map(([name, v]) => {
      const member = members.find((m) => m.name === name);
      return JSON.stringify(name) + ":" + toJson(v, struct, byName, member);
    });
    return "{" + parts.join(",") + "}";
  }
  return scalar(value);
}
