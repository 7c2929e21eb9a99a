// CDR samples decoded by Foxglove's own modules (@foxglove/omgidl-parser and
// @foxglove/omgidl-serialization), as JSON our YAML reader takes back: structs as objects,
// sequences and arrays as arrays, 64-bit integers as exact JSON integers, enum values as the
// names of their enumerators (Foxglove shows those; a value the enum lacks stays a number),
// non-finite floats as the YAML spellings ".nan", ".inf", "-.inf". Used by decode_cdr.mjs and
// components/bag/test/js/mcap_decode.mjs. `jsDir` is the repository's js/ folder.
import { createRequire } from "node:module";
import { join } from "node:path";

/// A decoder of the root type `schemaName` of the OMG IDL text `idl`: bytes -> JSON text.
export function cdrDecoder(jsDir, schemaName, idl) {
  const require = createRequire(join(jsDir, "package.json"));
  const { parseIDL } = require("@foxglove/omgidl-parser");
  const { MessageReader } = require("@foxglove/omgidl-serialization");
  const definitions = parseIDL(idl);
  const byName = new Map(definitions.map((d) => [d.name, d]));
  const reader = new MessageReader(schemaName, definitions);
  return (bytes) => toJson(reader.readMessage(bytes), byName.get(schemaName), byName);
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
