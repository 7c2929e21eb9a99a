#!/usr/bin/env python3
"""Generates the type support of the auv message set from its IDL files.

fastddsgen gives the C++ types and their CDR code; this script adds what neither
vendor generator gives: a MessageTraits<T> specialisation per struct (topic type
name, Fast DDS TopicDataType, the self-contained OMG IDL schema of idl_schema.py
and a CDR walker), YAML conversion in both directions (for `auv topic echo|pub`
and for tests), and a registry of every type by name.

The walker reads a payload as fastddsgen's code decodes it but allocates nothing
per element: it proves that every element a sequence claims is present before
the decoder sizes a std::vector for them (fastcdr checks a length only against
the bytes left, so each received byte could cost an element's in-memory size).

Only the IDL subset the message set uses is understood: modules, @final structs
with @key members, enums, typedefs, sequences, fixed arrays and #include lines.
Anything else is an error naming the file and line, so the subset cannot drift
silently.
"""
import os
import re
import sys

import idl_schema

PRIMITIVES = {
    "boolean": "bool", "octet": "uint8_t", "char": "char",
    "short": "int16_t", "unsigned short": "uint16_t",
    "long": "int32_t", "unsigned long": "uint32_t",
    "long long": "int64_t", "unsigned long long": "uint64_t",
    "float": "float", "double": "double", "string": "std::string",
}


class IdlError(Exception):
    pass


def tokenize(text, path):
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    tokens = []
    for lineno, line in enumerate(text.split("\n"), 1):
        line = line.split("//", 1)[0]
        if line.strip().startswith("#"):
            continue
        for tok in re.findall(r"::|[A-Za-z_][A-Za-z0-9_]*|\d+|@[A-Za-z_]+|[{}();,<>\[\]=:]|\S", line):
            if tok.startswith("_") and len(tok) > 1:
                tok = tok[1:]  # IDL 4 escaped identifier: both generators drop the underscore
            tokens.append((tok, lineno))
    return tokens


class Parser:
    def __init__(self, path):
        self.path = path
        with open(path) as f:
            self.toks = tokenize(f.read(), path)
        self.i = 0
        self.structs = []   # (scoped name, [members], keyed)
        self.enums = []     # (scoped name, [values])
        self.typedefs = {}  # scoped name -> type descriptor

    def error(self, msg):
        line = self.toks[min(self.i, len(self.toks) - 1)][1] if self.toks else 0
        raise IdlError(f"{self.path}:{line}: {msg}")

    def peek(self, k=0):
        return self.toks[self.i + k][0] if self.i + k < len(self.toks) else None

    def take(self, expected=None):
        if self.i >= len(self.toks):
            self.error(f"unexpected end of file, expected {expected}")
        tok = self.toks[self.i][0]
        if expected is not None and tok != expected:
            self.error(f"expected '{expected}', got '{tok}'")
        self.i += 1
        return tok

    def parse(self):
        self.parse_scope([])
        return self

    def parse_scope(self, scope):
        while self.peek() is not None and self.peek() != "}":
            annotations = []
            while self.peek() and self.peek().startswith("@"):
                annotations.append(self.take())
            kw = self.take()
            if kw == "module":
                name = self.take()
                self.take("{")
                self.parse_scope(scope + [name])
                self.take("}")
                self.take(";")
            elif kw == "struct":
                self.parse_struct(scope, annotations)
            elif kw == "enum":
                self.parse_enum(scope)
            elif kw == "const":  # constants are emitted by fastddsgen; nothing to add
                while self.take() != ";":
                    pass
            elif kw == "typedef":
                t = self.parse_type(scope)
                name = self.take()
                t = self.parse_array_suffix(t)
                self.take(";")
                self.typedefs["::".join(scope + [name])] = t
            else:
                self.error(f"unsupported IDL construct '{kw}'")

    def parse_type(self, scope):
        tok = self.take()
        if tok == "sequence":
            self.take("<")
            elem = self.parse_type(scope)
            if self.peek() == ",":
                self.take(",")
                self.take()
            self.take(">")
            return ("sequence", elem)
        if tok == "unsigned":
            tok += " " + self.take()
            if tok == "unsigned long" and self.peek() == "long":
                tok += " " + self.take()
            return ("prim", tok)
        if tok == "long" and self.peek() == "long":
            self.take()
            return ("prim", "long long")
        if tok == "string" and self.peek() == "<":
            self.take("<"); self.take(); self.take(">")
            return ("prim", "string")
        if tok in PRIMITIVES:
            return ("prim", tok)
        if tok in ("int8", "uint8", "wchar", "wstring", "any", "union", "fixed"):
            self.error(f"type '{tok}' is outside the supported subset")
        name = tok
        while self.peek() == "::":
            self.take("::")
            name += "::" + self.take()
        return ("named", self.resolve(name, scope))

    def resolve(self, name, scope):
        return name.lstrip(":") if "::" in name else "::".join(scope + [name])

    def parse_array_suffix(self, t):
        dims = []
        while self.peek() == "[":
            self.take("[")
            dims.append(int(self.take()))
            self.take("]")
        for d in reversed(dims):
            t = ("array", t, d)
        return t

    def parse_struct(self, scope, annotations):
        name = self.take()
        if "@final" not in annotations:
            self.error(f"struct {name} must be @final (cross-vendor interop, see README)")
        if self.peek() == ":":
            self.error(f"struct {name}: inheritance is outside the supported subset")
        self.take("{")
        members = []
        keyed = False
        while self.peek() != "}":
            anns = []
            while self.peek().startswith("@"):
                anns.append(self.take())
                if self.peek() == "(":
                    while self.take() != ")":
                        pass
            if any(a in ("@optional", "@external") for a in anns):
                self.error(f"{name}: {anns} is outside the supported subset")
            t = self.parse_type(scope)
            while True:
                member = self.take()
                mt = self.parse_array_suffix(t)
                members.append((member, mt, "@key" in anns))
                keyed = keyed or "@key" in anns
                if self.peek() == ",":
                    self.take(",")
                    continue
                break
            self.take(";")
        self.take("}")
        self.take(";")
        self.structs.append(("::".join(scope + [name]), members, keyed))

    def parse_enum(self, scope):
        name = self.take()
        self.take("{")
        values = []
        while self.peek() != "}":
            values.append(self.take())
            if self.peek() == ",":
                self.take(",")
        self.take("}")
        self.take(";")
        self.enums.append(("::".join(scope + [name]), values))


def cpp_type(t, typedefs):
    kind = t[0]
    if kind == "prim":
        return PRIMITIVES[t[1]]
    if kind == "sequence":
        return f"std::vector<{cpp_type(t[1], typedefs)}>"
    if kind == "array":
        return f"std::array<{cpp_type(t[1], typedefs)}, {t[2]}>"
    return t[1]


def walk_statements(t, typedefs, enum_names, depth=0):
    """C++ statements reading one value of type `t` from `cdr` as fastddsgen's code does."""
    kind = t[0]
    if kind == "named" and t[1] in typedefs:
        return walk_statements(typedefs[t[1]], typedefs, enum_names, depth)
    if kind == "prim":
        return [f"{{ {PRIMITIVES[t[1]]} value; cdr >> value; }}"]
    if kind == "named":
        if t[1] in enum_names:  # fastddsgen: (uint32_t&)
            return ["{ uint32_t value; cdr >> value; }"]
        return [f"MessageTraits<{t[1]}>::walkCdr(cdr);"]
    i = f"i{depth}"
    if kind == "array":
        inner = walk_statements(t[1], typedefs, enum_names, depth + 1)
        return [f"for (int {i} = 0; {i} < {t[2]}; ++{i}) {{"] + ["  " + s for s in inner] + ["}"]
    elem = t[1]
    while elem[0] == "named" and elem[1] in typedefs:
        elem = typedefs[elem[1]]
    n = f"n{depth}"
    if elem[0] == "prim" and elem[1] != "string":
        # Contiguous and aligned once: the first element aligns, the rest is skipped.
        c = PRIMITIVES[elem[1]]
        return [f"{{ uint32_t {n} = 0; cdr >> {n};",
                f"  if ({n} > 0) {{ {c} first; cdr >> first; "
                f"detail::skipCdr(cdr, (size_t({n}) - 1) * sizeof({c})); }} }}"]
    inner = walk_statements(elem, typedefs, enum_names, depth + 1)
    return ([f"{{ uint32_t {n} = 0; cdr >> {n};", f"  for (uint32_t {i} = 0; {i} < {n}; ++{i}) {{"]
            + ["    " + s for s in inner] + ["  }", "}"])


def main():
    if len(sys.argv) < 5:
        sys.exit("usage: gen_type_support.py OUT_HEADER OUT_SOURCE IDLC_DIR FILE.idl...")
    out_h, out_cc, idlc_dir, idls = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    structs, enums, typedefs = [], [], {}
    try:
        for path in idls:
            p = Parser(path).parse()
            structs += p.structs
            enums += p.enums
            typedefs.update(p.typedefs)
        schemas = idl_schema.build_schemas(idls, structs, typedefs)
    except (IdlError, idl_schema.SchemaError) as e:
        sys.exit(f"gen_type_support: {e}")
    enum_names = {e[0] for e in enums}
    struct_names = {s[0] for s in structs}
    for name, members, _ in structs:
        for m, t, _k in members:
            base = t
            while base[0] in ("sequence", "array"):
                base = base[1]
            if base[0] == "named" and base[1] not in enum_names | struct_names | set(typedefs):
                sys.exit(f"gen_type_support: {name}.{m}: unknown type '{base[1]}'")

    bases = [os.path.splitext(os.path.basename(p))[0] for p in idls]
    h = ["// Generated by idl/tools/gen_type_support.py from the auv IDL files. Do not edit.",
         "#pragma once", "", '#include "auv/msg/type_support.h"', ""]
    h += [f'#include "auv/msg/{b}.h"' for b in bases]
    h += [f'#include "auv/msg/{b}PubSubTypes.h"' for b in bases]
    h += ["", "namespace auv::msg {", ""]
    for name, values in enums:
        h.append(f"template <> struct EnumTraits<{name}> {{")
        h.append("  static constexpr bool kIsEnum = true;")
        h.append(f"  static constexpr std::array<const char*, {len(values)}> kNames = {{")
        h.append("      " + ", ".join(f'"{v}"' for v in values) + "};")
        h.append("};")
    h.append("")
    for name, members, keyed in structs:
        short = name.split("::")[-1]
        h.append(f"YAML::Node toYaml(const {name}& msg);")
        h.append(f"void fromYaml(const YAML::Node& node, {name}& msg, const std::string& path);")
        h.append(f"template <> struct MessageTraits<{name}> {{")
        h.append(f"  using PubSubType = {name}PubSubType;")
        h.append(f'  static constexpr const char* kTypeName = "{name}";')
        h.append(f"  static constexpr bool kKeyed = {'true' if keyed else 'false'};")
        h.append("  static const char* omgIdl();  // the schema text, see TypeSupport::omg_idl")
        h.append("  /// Reads one sample as the decoder does, allocating nothing per element; throws")
        h.append("  /// fastcdr's NotEnoughMemoryException where the bytes end (GuardedPubSubType).")
        h.append("  static void walkCdr(eprosima::fastcdr::Cdr& cdr);")
        h.append("};")
        h.append("")
    h += ["}  // namespace auv::msg", ""]

    cc = ["// Generated by idl/tools/gen_type_support.py from the auv IDL files. Do not edit.",
          '#include "auv/msg/all.h"', "", '#include "auv/msg/yaml_convert.h"', "",
          "namespace auv::msg {", ""]
    for name, members, keyed in structs:
        cc.append(f"YAML::Node toYaml(const {name}& msg) {{")
        cc.append("  YAML::Node node(YAML::NodeType::Map);")
        for m, t, _ in members:
            cc.append(f'  node["{m}"] = detail::encode(msg.{m}());')
        cc.append("  return node;")
        cc.append("}")
        cc.append("")
        cc.append(f"void fromYaml(const YAML::Node& node, {name}& msg, const std::string& path) {{")
        fields = ", ".join(f'"{m}"' for m, _, _ in members)
        cc.append(f"  detail::checkFields(node, path, {{{fields}}});")
        for m, t, _ in members:
            cc.append(f'  if (node["{m}"]) detail::decode(node["{m}"], msg.{m}(), detail::join(path, "{m}"));')
        cc.append("}")
        cc.append("")
    for name, members, _ in structs:
        cc.append(f"void MessageTraits<{name}>::walkCdr(eprosima::fastcdr::Cdr& cdr) {{")
        for m, t, _ in members:
            cc += ["  " + s for s in walk_statements(t, typedefs, enum_names)]
        cc.append("}")
        cc.append("")
    for name, _, _ in structs:
        if ")auv_idl\"" in schemas[name]:
            sys.exit(f"gen_type_support: {name}: schema text holds the raw string delimiter")
        cc.append(f"const char* MessageTraits<{name}>::omgIdl() {{")
        cc.append(f'  return R"auv_idl({schemas[name]})auv_idl";')
        cc.append("}")
        cc.append("")
    cc.append("const std::vector<TypeSupport>& allTypes() {")
    cc.append("  static const std::vector<TypeSupport> types = {")
    for name, _, _ in structs:
        cc.append(f"      makeTypeSupport<{name}>(),")
    cc.append("  };")
    cc.append("  return types;")
    cc.append("}")
    cc += ["", "}  // namespace auv::msg", ""]

    # For the test that checks idlc (Cyclone) and fastddsgen (Fast DDS) agree on every name.
    inc_h = ["#pragma once"] + [f'#include "{os.path.join(idlc_dir, b)}.h"' for b in bases]
    inc = [f'AUV_IDLC_TYPE({n.replace("::", "_")}_desc, "{n}", {"true" if k else "false"})'
            for n, _, k in structs]
    out_inc = os.path.join(idlc_dir, "idlc_check", "idlc_descriptors.inc")
    out_inc_h = os.path.join(idlc_dir, "idlc_check", "idlc_headers.h")
    os.makedirs(os.path.dirname(out_inc), exist_ok=True)
    for path, lines in ((out_h, h), (out_cc, cc), (out_inc, inc), (out_inc_h, inc_h)):
        text = "\n".join(lines)
        if os.path.exists(path) and open(path).read() == text:
            continue
        with open(path, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
