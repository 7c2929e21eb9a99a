"""Self-contained OMG IDL schemas of the auv message set, one per struct.

A schema is what MCAP and Foxglove call `omgidl`: the text of the root type and of every
struct and enum it uses, in dependency order, with no #include, so a reader that knows
nothing else can decode the type's CDR. Declarations are copied from idl/msg/*.idl with their
comments (units and frames stay with the data); only the code is normalised for readers that
implement less of IDL than fastddsgen and idlc do:

* escaped identifiers lose their '_' (`_header` -> `header`, `_String` -> `String`), as the
  IDL 4 spec and both generators read them: field names then match the C++ members, the YAML
  of `auv topic echo` and the DDS type name (`auv::msg::String`). Foxglove's parser would
  keep the '_'. The price: `Header header;` collides with `Header` ignoring case, which
  fastddsgen and idlc refuse, so a schema is for decoding, not for code generation.
* integer literals are decimal (Foxglove's parser does not read `0x...`).
* preprocessor lines are dropped.

The module also keeps the constants (bit flags) of the root type's own file, placed just
before the root type.
"""
import re

_TOKEN = re.compile(
    r"(?P<comment>//[^\n]*|/\*.*?\*/)"
    r"|(?P<preproc>^[ \t]*#[^\n]*)"
    r"|(?P<ws>\s+)"
    r"|(?P<string>\"(?:[^\"\\\n]|\\.)*\")"
    r"|(?P<hex>0[xX][0-9a-fA-F]+)"
    r"|(?P<ident>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<other>::|.)",
    re.S | re.M)


class SchemaError(Exception):
    pass


def _lex(text):
    return [(m.lastgroup, m.group(0)) for m in _TOKEN.finditer(text)]


def _normalise(kind, text):
    if kind == "ident" and text.startswith("_") and len(text) > 1:
        return text[1:]
    if kind == "hex":
        return str(int(text, 16))
    return text


def _leading_comments(tokens, first, floor):
    """Index of the first token of the comment block right above tokens[first] (no blank line
    in between, nothing before `floor`), or `first` when there is none."""
    start = first
    i = first - 1
    while i >= floor:
        kind, text = tokens[i]
        if kind == "ws":
            if text.count("\n") > 1:
                break
            i -= 1
            continue
        if kind == "comment":
            start = i
            i -= 1
            continue
        break
    return start


class Declaration:
    def __init__(self, kind, name, path, text):
        self.kind = kind  # "struct", "enum", "const" or "typedef"
        self.name = name  # scoped, e.g. "auv::msg::Odometry"
        self.path = path
        self.text = text


def scan(path):
    """The module-level declarations of one .idl file, in file order."""
    with open(path) as f:
        tokens = _lex(f.read())
    decls = []
    scope = []
    i = 0
    floor = 0  # end of the previous declaration: its comments are not the next one's
    code = lambda j: tokens[j][0] not in ("ws", "comment", "preproc")
    while i < len(tokens):
        if not code(i):
            i += 1
            continue
        kind, text = tokens[i]
        if text == "module":
            j = i + 1
            while not code(j):
                j += 1
            scope.append(_normalise(*tokens[j]))
            while tokens[j][1] != "{":
                j += 1
            i = j + 1
            continue
        if text == "}":  # end of a module: "};"
            scope.pop()
            while tokens[i][1] != ";":
                i += 1
            i += 1
            continue
        # A declaration: annotations, keyword, name ... ';' at brace depth 0.
        first = i
        depth = 0
        words = []
        while True:
            k, t = tokens[i]
            if t == "{":
                depth += 1
            elif t == "}":
                depth -= 1
            elif t == ";" and depth == 0:
                break
            if k == "ident" and depth == 0:
                words.append(_normalise(k, t))
            i += 1
            if i >= len(tokens):
                raise SchemaError(f"{path}: unterminated declaration")
        end = i + 1
        # A comment on the same line as the ';' belongs to the declaration.
        if end + 1 < len(tokens) and tokens[end][0] == "ws" and "\n" not in tokens[end][1] \
                and tokens[end + 1][0] == "comment":
            end += 2
        keyword = next((w for w in words if w in ("struct", "enum", "const", "typedef")), None)
        if keyword is None:
            raise SchemaError(f"{path}: unsupported declaration '{' '.join(words[:3])}'")
        if keyword in ("struct", "enum"):
            name = words[words.index(keyword) + 1]
        elif keyword == "const":
            name = _const_name(tokens[first:end])
        else:
            name = words[-1]  # typedef T NAME;
        start = _leading_comments(tokens, first, floor)
        body = "".join(_normalise(k, t) for k, t in tokens[start:end] if k != "preproc")
        decls.append(Declaration(keyword, "::".join(scope + [name]), path, body.strip("\n")))
        i = floor = end
    return decls


def _const_name(tokens):
    """NAME of `const T NAME = value;`: the last identifier before '='."""
    name = None
    for kind, text in tokens:
        if text == "=":
            break
        if kind == "ident":
            name = _normalise(kind, text)
    return name


def _wrap(decls):
    """Declarations in module blocks, reopened whenever the scope changes."""
    out = []
    current = []
    for d in decls:
        scope = d.name.split("::")[:-1]
        if scope != current:
            out += ["};"] * len(current)
            out += [f"module {m} {{" for m in scope]
            current = scope
        out += ["", d.text]
    out += [""] + ["};"] * len(current)
    return "\n".join(out) + "\n"


def build_schemas(idl_paths, structs, typedefs):
    """{root struct name: schema text} for every struct.

    `structs` are (scoped name, [(member, type, key)], keyed) from gen_type_support's parser
    and `typedefs` its {scoped name: type}; types are ("prim", ...), ("named", scoped),
    ("sequence", t) or ("array", t, n)."""
    decls = {}
    consts_of = {}
    for path in idl_paths:
        for d in scan(path):
            if d.kind == "const":
                consts_of.setdefault(path, []).append(d)
            else:
                decls[d.name] = d
    members = {name: [t for _, t, _ in ms] for name, ms, _ in structs}

    def named(t):
        while t[0] in ("sequence", "array"):
            t = t[1]
        return [t[1]] if t[0] == "named" else []

    def deps(name):
        if name in members:
            return [n for t in members[name] for n in named(t)]
        if name in typedefs:
            return named(typedefs[name])
        return []  # enum

    schemas = {}
    for root in members:
        if root not in decls:
            raise SchemaError(f"{root}: declaration not found in the IDL text")
        order, seen = [], set()

        def visit(name):
            if name in seen:
                return
            seen.add(name)
            for dep in deps(name):
                visit(dep)
            if name not in decls:
                raise SchemaError(f"{root}: uses {name}, whose declaration was not found")
            order.append(decls[name])

        for dep in deps(root):
            visit(dep)
        consts = consts_of.get(decls[root].path, [])
        if consts:  # one block, as in the file
            order.append(Declaration("const", consts[0].name, consts[0].path,
                                     "\n".join(c.text for c in consts)))
        order.append(decls[root])
        header = (f"// {root} and the types it uses, from the auv message set (idl/msg).\n"
                  "// Escaped identifiers are written without their '_', integers in decimal.\n")
        schemas[root] = header + _wrap(order)
    return schemas
