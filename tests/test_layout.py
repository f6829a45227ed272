"""The package's layout and contracts, read from its source: who imports whom, one home per rule
of spec/FORMAT.md §11, function sizes, and what the tools may use."""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "tuckercodec"
SPEC = ROOT / "spec" / "FORMAT.md"
FORMAT_ERRORS = {
    "FormatError",
    "TruncatedFileError",
    "ChecksumError",
    "UnsupportedVersionError",
    "LimitError",
}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@cache
def _modules() -> dict[str, Path]:
    return {_module_name(path): path for path in PACKAGE.rglob("*.py")}


@cache
def _imports(module: str) -> frozenset[str]:
    """The package modules ``module`` imports directly (``from . import x`` names module x)."""
    modules = _modules()
    path = modules[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, base]) if base else ".".join(anchor)
            names = [f"{base}.{alias.name}" for alias in node.names]
            names = [name if name in modules else base for name in names]
        else:
            continue
        found.update(name for name in names if name in modules and name != module)
    return frozenset(found)


def _reachable(module: str) -> set[str]:
    """Every package module ``module`` imports, directly or through others (not counting the
    parent packages Python imports first, which only re-export)."""
    seen: set[str] = set()
    pending = [module]
    while pending:
        for name in _imports(pending.pop()):
            if name not in seen:
                seen.add(name)
                pending.append(name)
    return seen


def _family(reached: set[str], prefix: str) -> set[str]:
    return {name for name in reached if name == prefix or name.startswith(prefix + ".")}


#: The package's layers, lowest first, and the top-level packages and modules each holds (""
#: is the package's own ``__init__``). ARCHITECTURE.md says what each knows.
LAYERS: tuple[tuple[str, frozenset[str]], ...] = (
    ("foundation", frozenset({"_version", "errors", "system"})),
    ("model", frozenset({"model"})),
    ("measures", frozenset({"measures"})),
    ("format", frozenset({"format"})),
    ("codec", frozenset({"decomposition", "encoder", "decoder"})),
    ("io", frozenset({"io"})),
    (
        "applications",
        frozenset(
            {"", "__main__", "files", "gltf_export", "reports", "cli", "blender", "web"}
            | {"zarr_codec", "internal"}
        ),
    ),
)


def _unit(module: str) -> str:
    """The top-level package or module of the package that ``module`` belongs to."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _layer(module: str) -> int:
    unit = _unit(module)
    found = [index for index, (_, units) in enumerate(LAYERS) if unit in units]
    assert found, f"{module}: its top-level unit {unit!r} is in no layer of LAYERS"
    return found[0]


def _layer_violations(edges: dict[str, frozenset[str]]) -> list[str]:
    """Every import (module -> imported) that goes up the layers."""
    return [
        f"{module} ({LAYERS[_layer(module)][0]}) imports {name} ({LAYERS[_layer(name)][0]})"
        for module in sorted(edges)
        for name in sorted(edges[module])
        if _layer(name) > _layer(module)
    ]


def test_every_module_belongs_to_one_layer():
    units = [units for _, units in LAYERS]
    assert sum(len(u) for u in units) == len(frozenset().union(*units)), "a unit in two layers"
    for module in _modules():
        _layer(module)


def test_every_import_goes_down_the_layers():
    violations = _layer_violations({module: _imports(module) for module in _modules()})
    assert not violations, "imports that go up the layers:\n" + "\n".join(violations)


def test_the_layer_check_sees_an_import_that_goes_up():
    """The check itself, on a made-up import: the model importing the codec is refused."""
    edges = {"tuckercodec.model.sequence": frozenset({"tuckercodec.encoder.options"})}
    assert _layer_violations(edges) == [
        "tuckercodec.model.sequence (model) imports tuckercodec.encoder.options (codec)"
    ]
    assert not _layer_violations({"tuckercodec.encoder.options": frozenset(edges)})


def test_the_encoder_never_imports_the_decoder():
    for module in _family(set(_modules()), "tuckercodec.encoder"):
        assert not _family(_reachable(module), "tuckercodec.decoder"), module


def test_the_decoder_never_imports_the_encoder_or_the_error_measures():
    reached = _reachable("tuckercodec.decoder")
    forbidden_families = (
        "tuckercodec.encoder",
        "tuckercodec.measures.distortion",
        "tuckercodec.measures.perceptual",
    )
    for forbidden in forbidden_families:
        assert not _family(reached, forbidden), forbidden


def test_io_imports_neither_the_format_nor_the_codec():
    """Reading and writing a cache needs no part of the codec (the codec reads through
    :class:`~tuckercodec.model.sources.FrameSource`)."""
    for module in _family(set(_modules()), "tuckercodec.io"):
        reached = _reachable(module)
        for layer in ("format", "decomposition", "encoder", "decoder"):
            assert not _family(reached, f"tuckercodec.{layer}"), (module, layer)


def test_the_format_package_knows_bytes_not_the_codec_around_it():
    for module in _family(set(_modules()), "tuckercodec.format"):
        reached = _reachable(module)
        for layer in ("encoder", "decoder", "io", "cli", "decomposition"):
            assert not _family(reached, f"tuckercodec.{layer}"), (module, layer)


def test_init_files_only_re_export():
    """An ``__init__.py`` holds no function or class of its own (the package root's lazy
    ``__getattr__`` and ``__dir__``, and a lazy package's, are the exception): code lives in
    modules whose names say what they hold."""
    allowed = {"__getattr__", "__dir__"}
    for path in sorted(PACKAGE.rglob("__init__.py")):
        defined = [
            node.name
            for node in ast.parse(path.read_text()).body
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)
            and node.name not in allowed
        ]
        assert not defined, f"{path.relative_to(ROOT)} defines {defined}: move them to a module"


def test_package_imports_form_no_cycle():
    for module in _modules():
        assert module not in _reachable(module), f"{module} imports itself through others"


# ------------------------------------------------------------------------------------------
# ARCHITECTURE.md's table: every numbered section of the spec, and the files that implement it

ARCHITECTURE = ROOT / "ARCHITECTURE.md"


def _spec_sections(spec: str) -> list[str]:
    """The numbers of spec/FORMAT.md's numbered sections (``## 6.`` and ``### 6.2``)."""
    return re.findall(r"^#{2,3} (\d+(?:\.\d+)*)\.? ", spec, re.M)


def _architecture_rows(text: str) -> dict[str, tuple[list[str], list[str]]]:
    """section number -> (Python files, JavaScript files) of ARCHITECTURE.md's spec table."""
    table = text[text.index("| spec section | Python | JavaScript |") :]
    rows: dict[str, tuple[list[str], list[str]]] = {}
    for line in table.splitlines()[2:]:
        if not line.startswith("|"):
            break
        section, python, javascript = (cell.strip() for cell in line.strip("|").split("|"))
        number = section.split()[0].rstrip(".")
        assert number not in rows, f"ARCHITECTURE.md lists section {number} twice"
        rows[number] = (re.findall(r"`([^`]+)`", python), re.findall(r"`([^`]+)`", javascript))
    return rows


def _architecture_problems(spec: str, text: str) -> list[str]:
    rows = _architecture_rows(text)
    problems = [f"section {n} is not in the table" for n in _spec_sections(spec) if n not in rows]
    problems += [f"section {n} is not in the spec" for n in rows if n not in _spec_sections(spec)]
    for number, (python, javascript) in rows.items():
        if not python:
            problems.append(f"section {number} names no Python module")
        problems += [
            f"section {number}: {name} does not exist"
            for name in python + javascript
            if not (ROOT / name).is_file()
        ]
    return problems


def test_the_architecture_table_covers_the_spec():
    assert len(_spec_sections(SPEC.read_text())) > 20
    problems = _architecture_problems(SPEC.read_text(), ARCHITECTURE.read_text())
    assert not problems, "ARCHITECTURE.md's spec table: " + "; ".join(problems)


def test_the_architecture_check_sees_a_missing_section_and_a_missing_file():
    spec = SPEC.read_text() + "\n### 12.1 A new part\n"
    text = ARCHITECTURE.read_text().replace(
        "`tuckercodec/format/qmat.py`", "`tuckercodec/format/qmat_gone.py`"
    )
    assert _architecture_problems(spec, text) == [
        "section 12.1 is not in the table",
        "section 6.3: tuckercodec/format/qmat_gone.py does not exist",
    ]


# ------------------------------------------------------------------------------------------
# one error contract: every rule of §11 raised from one place, with the class §11 names


def _spec_rules() -> dict[str, str]:
    """rule id -> error class, from the table of spec/FORMAT.md §11."""
    text = SPEC.read_text()
    section = text[text.index("## 11. Invalid files") : text.index("## 12.")]
    rows = re.findall(r"^\| *\d+ *\| *(R\d\d-[a-z0-9-]+) *\|.*\| *(\w+) *\|$", section, re.M)
    return dict(rows)


class _RaiseSites(ast.NodeVisitor):
    """Every construction of a FormatError class: (rule, class, module:function), where the
    function is the innermost one around it (``Class.method`` for a method)."""

    def __init__(self, module: str) -> None:
        self.module = module
        self.scope: list[str] = []
        self.sites: list[tuple[str, str, str]] = []

    def _enter(self, node: ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) -> None:
        self.scope.append(node.name)
        self.generic_visit(node)
        self.scope.pop()

    visit_ClassDef = visit_FunctionDef = visit_AsyncFunctionDef = _enter

    def visit_Call(self, node: ast.Call) -> None:
        if isinstance(node.func, ast.Name) and node.func.id in FORMAT_ERRORS:
            where = f"{self.module}:{'.'.join(self.scope)}"
            rule = next((k.value for k in node.keywords if k.arg == "rule"), None)
            assert isinstance(rule, ast.Constant), f"{where} (line {node.lineno}): no literal rule="
            self.sites.append((str(rule.value), node.func.id, where))
        self.generic_visit(node)


def _raise_sites() -> list[tuple[str, str, str]]:
    sites = []
    for module, path in _modules().items():
        visitor = _RaiseSites(module)
        visitor.visit(ast.parse(path.read_text()))
        sites += visitor.sites
    return sites


def test_the_spec_lists_47_rules_each_with_its_class():
    rules = _spec_rules()
    assert len(rules) == 47
    assert set(rules.values()) <= FORMAT_ERRORS


def test_every_rule_is_raised_from_exactly_one_function_with_the_class_the_spec_gives():
    """One home per rule. That every rule also has its invalid vector, which raises that rule
    id, is tests/test_format_vectors.py's to check."""
    rules = _spec_rules()
    homes: dict[str, set[str]] = {}
    for rule, error, where in _raise_sites():
        assert rule in rules, f"{where} raises {rule}, which §11 does not list"
        assert error == rules[rule], f"{where} raises {rule} as {error}, §11 says {rules[rule]}"
        homes.setdefault(rule, set()).add(where)
    scattered = {rule: sorted(places) for rule, places in homes.items() if len(places) > 1}
    assert not scattered, f"rules raised from more than one function: {scattered}"
    assert set(homes) == set(rules), f"never raised: {sorted(set(rules) - set(homes))}"


# ------------------------------------------------------------------------------------------
# sizes and surfaces

#: The length rule: what a reader must hold at once is a function, not a module, so
#: the package caps functions and leaves a module to be as long as its one concern.
FUNCTION_LINES = 120
LONG_FUNCTION_LINES = 80
LONG_FUNCTIONS_ALLOWED = 2


class _FunctionLengths(ast.NodeVisitor):
    """(lines, where) of every function and method, nested ones included (each counted alone
    and inside the function around it): ``where`` is ``file:Class.method`` or ``file:outer.inner``.
    A function's lines run from its ``def`` line to the last line of its body, docstring and
    comments included, decorators excluded."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.scope: list[str] = []
        self.lengths: list[tuple[int, str]] = []

    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        self.scope.append(node.name)
        self.generic_visit(node)
        self.scope.pop()

    def _function(self, node: ast.FunctionDef | ast.AsyncFunctionDef) -> None:
        self.scope.append(node.name)
        assert node.end_lineno is not None
        lines = node.end_lineno - node.lineno + 1  # lineno is the def's, after any decorator
        self.lengths.append((lines, f"{self.file}:{'.'.join(self.scope)}"))
        self.generic_visit(node)
        self.scope.pop()

    visit_FunctionDef = visit_AsyncFunctionDef = _function


def _function_lengths(source: str, file: str) -> list[tuple[int, str]]:
    visitor = _FunctionLengths(file)
    visitor.visit(ast.parse(source))
    return visitor.lengths


def test_function_length_counts_from_def_to_the_end_of_the_body():
    source = (
        "import functools\n"
        "@functools.lru_cache(\n"
        "    maxsize=None,\n"
        ")\n"
        "def f():\n"
        '    """Doc."""\n'
        "\n"
        "    # a comment\n"
        "    return 1\n"
        "class C:\n"
        "    async def g(self):\n"
        "        def h():\n"
        "            pass\n"
        "        return h\n"
    )
    assert sorted(_function_lengths(source, "m.py")) == [
        (2, "m.py:C.g.h"),
        (4, "m.py:C.g"),
        (5, "m.py:f"),
    ]


def test_no_function_is_long():
    """No function of the package over FUNCTION_LINES (120) lines, and no more than
    LONG_FUNCTIONS_ALLOWED (2) over LONG_FUNCTION_LINES (80). A function's lines are counted from
    its ``def`` line to the last line of its body: decorators excluded, its docstring, comments,
    blank lines and nested functions included."""
    lengths: list[tuple[int, str]] = []
    for path in sorted(PACKAGE.rglob("*.py")):
        lengths += _function_lengths(path.read_text(), str(path.relative_to(ROOT)))
    assert len(lengths) > 500, "too few functions found: is the package there?"
    listed = sorted(lengths, reverse=True)
    over_cap = [f"{where} ({lines} lines)" for lines, where in listed if lines > FUNCTION_LINES]
    assert not over_cap, (
        f"functions longer than {FUNCTION_LINES} lines, split them: {', '.join(over_cap)}"
    )
    long = [f"{where} ({lines} lines)" for lines, where in listed if lines > LONG_FUNCTION_LINES]
    assert len(long) <= LONG_FUNCTIONS_ALLOWED, (
        f"{len(long)} functions longer than {LONG_FUNCTION_LINES} lines, at most "
        f"{LONG_FUNCTIONS_ALLOWED} may be: {', '.join(long)}"
    )


def test_the_javascript_side_keeps_the_same_function_sizes():
    """tools/js/function_sizes.mjs holds our JavaScript to the same three numbers."""
    script = (ROOT / "tools" / "js" / "function_sizes.mjs").read_text()
    for name, value in (
        ("FUNCTION_LINES", FUNCTION_LINES),
        ("LONG_FUNCTION_LINES", LONG_FUNCTION_LINES),
        ("LONG_FUNCTIONS_ALLOWED", LONG_FUNCTIONS_ALLOWED),
    ):
        assert re.search(rf"^export const {name} = {value};$", script, re.M), name


def _tool_imports() -> list[tuple[str, str]]:
    """(tool file, imported tuckercodec module) for every import of the package in tools/."""
    found = []
    for path in sorted((ROOT / "tools").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                found += [
                    (path.name, a.name) for a in node.names if a.name.startswith("tuckercodec")
                ]
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("tuckercodec"):
                module = node.module or ""
                names = [a.name for a in node.names]
                if module == "tuckercodec" and "internal" in names:
                    found.append((path.name, "tuckercodec.internal"))
                    names.remove("internal")
                if names:
                    found.append((path.name, module))
    return found


def test_tools_use_only_the_public_api_and_the_documented_internal_surface():
    imports = _tool_imports()
    assert imports, "tools/ imports nothing from tuckercodec: is the folder there?"
    strays = [
        (tool, module)
        for tool, module in imports
        if module not in {"tuckercodec", "tuckercodec.internal"}
    ]
    assert not strays, f"tools reach past tuckercodec and tuckercodec.internal: {strays}"


def test_no_test_or_tool_edits_sys_path():
    for folder in ("tests", "tools"):
        for path in (ROOT / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if (
                    isinstance(node, ast.Attribute)
                    and node.attr == "path"
                    and isinstance(node.value, ast.Name)
                    and node.value.id == "sys"
                ):
                    raise AssertionError(f"{path.relative_to(ROOT)}:{node.lineno} uses sys.path")


def test_the_package_ships_its_type_information():
    assert (PACKAGE / "py.typed").exists()


# ------------------------------------------------------------------------------------------
# no tracker references: a reader of the repository cannot see the tracker, so a comment, a
# docstring or a document says the reason in words instead of pointing at an issue's number

#: "issue" or "issues", a space, perhaps "#", and a number (written so as not to match itself).
TRACKER_REFERENCE = re.compile(r"\b[Ii]ssues? #?\d+")
#: The package, the tools, the tests, the spec and docs, and the top-level documents.
CHECKED_FOLDERS = ("tuckercodec", "tools", "tests", "spec", "docs")
CHECKED_SUFFIXES = {".py", ".md", ".toml", ".js", ".mjs", ".ts", ".mts", ".html", ".css", ".txt"}
#: Installed or third-party code, not the project's words.
UNCHECKED_FOLDERS = {"node_modules", "vendor", "__pycache__"}


def _text_files(folder: Path) -> list[Path]:
    files = []
    for path in folder.iterdir():
        if path.is_dir() and path.name not in UNCHECKED_FOLDERS:
            files += _text_files(path)
        elif path.is_file() and path.suffix in CHECKED_SUFFIXES:
            files.append(path)
    return files


def _checked_files() -> list[Path]:
    files = [p for p in ROOT.iterdir() if p.is_file() and p.suffix in {".md", ".toml"}]
    for folder in CHECKED_FOLDERS:
        files += _text_files(ROOT / folder)
    return sorted(files)


def _tracker_references(files: list[Path], root: Path = ROOT) -> list[str]:
    found = []
    for path in files:
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if TRACKER_REFERENCE.search(line):
                found.append(f"{path.relative_to(root)}:{number}: {line.strip()}")
    return found


def test_no_comment_or_document_cites_a_tracker_issue_number():
    files = _checked_files()
    assert ROOT / "README.md" in files and Path(__file__) in files and len(files) > 300
    found = _tracker_references(files)
    assert not found, "tracker issue numbers; say the reason instead:\n" + "\n".join(found)


def test_a_tracker_issue_number_is_found(tmp_path):
    number = 22  # the citations below are made at run time, so this file cites none
    cited = tmp_path / "cited.py"
    lines = [
        f"# a crafted file (Issue {number}, finding 7)",
        f"x = 1  # issues {number - 17} and {number}",
        f"# see issue #{number}",
        "# an issue of the format, 22 issues, tissue 3",
    ]
    cited.write_text("\n".join(lines))
    assert _tracker_references([cited], tmp_path) == [
        f"cited.py:{n}: {lines[n - 1]}" for n in (1, 2, 3)
    ]
