"""The house rules of docs/ARCHITECTURE.md, read from the source (ast, nothing imported).

Reference: the layer order written below (the same table as docs/ARCHITECTURE.md). Every
``import`` of hawt_core and hawt_ros is parsed, also those inside functions (a lazy import
is an arrow too); an arrow from a lower layer to a higher one fails, as does any circle of
modules, an import of hawt_ros or rclpy from hawt_core, and a module over MAX_LINES lines.
Exact (no tolerance).
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: hawt_core's folders from the bottom up: a module may import its own layer and those below.
#: results sit below analyses because the analyses build result objects; plotting is part
#: of results (it draws result objects, it never runs an analysis).
CORE_LAYERS = [
    ("numerics",),
    ("model", "io"),
    ("fem", "rigid", "aero"),
    ("assembly",),
    ("solvers",),
    ("results",),
    ("control",),
    ("analyses",),
    ("cli",),
]

#: hawt_ros from the bottom up (above all of hawt_core).
ROS_LAYERS = [
    ("params", "backend", "geometry", "analysis_workers"),
    ("bag",),
    ("node", "cli"),
    ("commands",),
]

MAX_LINES = 800

#: Outside packages hawt_core may not import (the core never depends on the ROS side).
CORE_FORBIDDEN = ("hawt_ros", "hawt_msgs", "rclpy", "rosidl_runtime_py", "mcap")


def _modules(package: str) -> dict:
    """Dotted module name -> path of every .py file of ``package``."""
    out = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = {**_modules("hawt_core"), **_modules("hawt_ros")}


def _is_package(name: str) -> bool:
    return MODULES.get(name, Path()).name == "__init__.py"


def _imports(name: str, path: Path) -> list:
    """(imported dotted name, line) of every import in the file; relative imports resolved,
    ``from package import submodule`` resolved to the submodule."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = name if _is_package(name) else name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.append((sub if sub in MODULES else target, node.lineno))
    return found


def _owner(name: str) -> str:
    """The module of ours that a dotted name belongs to (longest prefix), or ''."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _layer(module: str):
    """(package, layer index) of one of our modules; None for a package's top __init__."""
    parts = module.split(".")
    if len(parts) < 2:
        return None
    layers = CORE_LAYERS if parts[0] == "hawt_core" else ROS_LAYERS
    for i, names in enumerate(layers):
        if parts[1] in names:
            return parts[0], i
    raise AssertionError(f"{module}: folder {parts[1]!r} is in no layer of "
                         "tests/test_architecture.py (add it to the table and to "
                         "docs/ARCHITECTURE.md)")


def _graph() -> dict:
    """module -> {imported module of ours: first line}."""
    graph = {}
    for name, path in MODULES.items():
        edges = {}
        for target, line in _imports(name, path):
            owner = _owner(target)
            if owner and owner != name:
                edges.setdefault(owner, line)
        graph[name] = edges
    return graph


GRAPH = _graph()


def test_every_folder_is_in_a_layer():
    for module in MODULES:
        _layer(module)


def test_imports_only_go_down_the_pipeline():
    """An arrow from a lower layer to a higher one fails (hawt_core is below hawt_ros)."""
    up = []
    for module, edges in GRAPH.items():
        here = _layer(module)
        for target, line in edges.items():
            there = _layer(target)
            if here is None or there is None:
                continue
            if here[0] == "hawt_core" and there[0] == "hawt_ros":
                up.append(f"{MODULES[module].relative_to(ROOT)}:{line} imports {target}")
            elif here[0] == there[0] and there[1] > here[1]:
                up.append(f"{MODULES[module].relative_to(ROOT)}:{line} imports {target} "
                          f"(layer {there[1]} above {here[1]})")
    assert not up, "imports up the pipeline:\n" + "\n".join(up)


def test_no_import_circles():
    """Tarjan's strongly connected components of the module graph: every one is a single
    module (a package's __init__ re-exporting its children counts as a module)."""
    index, low, stack, on_stack, circles = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in GRAPH:
        if v not in index:
            visit(v)
    assert not circles, "import circles: " + "; ".join(" <-> ".join(c) for c in circles)


def test_core_never_imports_ros():
    bad = []
    for name, path in MODULES.items():
        if not name.startswith("hawt_core"):
            continue
        for target, line in _imports(name, path):
            if target.split(".")[0] in CORE_FORBIDDEN:
                bad.append(f"{path.relative_to(ROOT)}:{line} imports {target}")
    assert not bad, "\n".join(bad)


def test_numerics_imports_nothing_else_of_hawt():
    bad = [f"{m} imports {t}" for m, edges in GRAPH.items() if m.startswith("hawt_core.numerics")
           for t in edges if not t.startswith("hawt_core.numerics")]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_module_size(name):
    lines = MODULES[name].read_text().count("\n")
    assert lines <= MAX_LINES, f"{MODULES[name].relative_to(ROOT)} has {lines} lines " \
                               f"(at most {MAX_LINES}: split it by concern)"


def test_the_rules_catch_an_arrow_up_and_a_circle(monkeypatch):
    """Probe of the test itself: an arrow numerics -> analyses, and a circle made from it,
    are found."""
    fake = {m: dict(e) for m, e in GRAPH.items()}
    fake["hawt_core.numerics.checks"]["hawt_core.analyses.modal"] = 1
    monkeypatch.setitem(globals(), "GRAPH", fake)
    with pytest.raises(AssertionError, match="layer 7 above 0"):
        test_imports_only_go_down_the_pipeline()
    with pytest.raises(AssertionError, match="import circles"):
        test_no_import_circles()
