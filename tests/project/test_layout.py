"""The package's import graph, module by module, read with ``ast`` (nothing is imported):
no cycle between modules, no import up the layers (``LAYERS`` in pytest_flockai/_layers.py,
printed on docs/explanation/architecture.md), and no two modules or packages in
different homes named alike (``report.py`` beside ``reports/``, ``markers`` meaning the
plugin's marks in one package and ArUco tags in another).

The graph has two kinds of edges: an import at module level (run when the module
is imported; imports under ``if TYPE_CHECKING:`` are left out, they never run) and a
lazy one, run later: an import inside a function, or a package's PEP 562 table
(``_LAZY``, ``_PUBLIC``: public name -> module, imported on first use). A cycle through
a lazy edge does not fail at import time, but it is still a cycle: each module
needs the other, so neither can be understood, tested or moved alone."""

from __future__ import annotations

import ast
import importlib
import re
import warnings
from pathlib import Path

import pytest
from test_architecture import SAME_LAYER, _layer_of

from pytest_flockai import _deprecation

PKG = Path(__file__).resolve().parents[2] / "pytest_flockai"

#: names alike in different homes, each a decision: (name, {the modules}) -> why they may
#: share it. Everything else named alike fails (rename one, or add it here with its reason).
ALIKE = {
    # a package's base classes live in its ``base`` module: the word means one thing
    ("base", frozenset({"policy/base", "probes/base", "sensors/base"})):
        "each package's own base class (Policy, Probe, Sensor)",
    # the batched backend mirrors the core module it reimplements, so that each
    # batched module has one twin (tests/sweeps/test_batched_twins.py pairs them by name)
    ("control", frozenset({"control", "sweeps/batched/control"})): "batched twin",
    ("energy", frozenset({"energy", "sweeps/batched/energy"})): "batched twin",
    ("param", frozenset({"airframe/params", "sweeps/batched/params"})): "batched twin",
    # the pytest side of a concept is harness/<concept>: the fixture and options of it
    ("sweep", frozenset({"harness/sweeps", "sweeps"})): "harness/ is the pytest face of sweeps/",
    # one meaning in two homes: a pilot flies the drone (app/ holds the pilots a MAVLink
    # app's commands fly, control/ the built-in ones); a datasheet is a published spec
    # sheet (of a drone in airframe/, of a computer in compute/)
    ("pilot", frozenset({"app/pilots", "control/pilots"})): "one meaning: a Pilot",
    ("datasheet", frozenset({"airframe/datasheet", "compute/datasheets"})):
        "one meaning: a published spec sheet",
}


def _dotted(path: Path) -> str:
    parts = list(path.relative_to(PKG.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_dotted(p): p for p in sorted(PKG.rglob("*.py"))}


def _package(module: str) -> str:
    return module if MODULES[module].name == "__init__.py" else module.rpartition(".")[0]


def _absolute(module: str, level: int, name: str | None) -> str:
    base = _package(module).split(".")
    base = base[:len(base) - (level - 1)] if level > 1 else base
    return ".".join(base + ([name] if name else []))


def _known(target: str) -> str | None:
    """The module of the package that ``import target`` runs (the nearest one above)."""
    while target and target not in MODULES:
        target = target.rpartition(".")[0]
    return target or None


def _import_targets(module: str, node: ast.Import | ast.ImportFrom) -> set[str]:
    if isinstance(node, ast.Import):
        return {t for a in node.names if a.name.startswith("pytest_flockai")
                and (t := _known(a.name))}
    if node.level == 0 and not (node.module or "").startswith("pytest_flockai"):
        return set()
    home = _absolute(module, node.level, node.module) if node.level else str(node.module)
    # ``from pkg import sub``: the submodule when there is one, else pkg's own module
    return {t for a in node.names if (t := _known(f"{home}.{a.name}") if f"{home}.{a.name}"
                                      in MODULES else _known(home))}


def _is_type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None)
    return isinstance(node, ast.If) and (getattr(test, "id", None) == "TYPE_CHECKING"
                                         or getattr(test, "attr", None) == "TYPE_CHECKING")


def _lazy_tables(module: str, tree: ast.Module) -> set[str]:
    """Modules named in a PEP 562 table: in a module that calls ``import_module``, a
    module-level dict whose values are relative module names (``".store"``) or
    (module, attribute) pairs."""
    found: set[str] = set()
    if not any(isinstance(n, ast.Name) and n.id.endswith("import_module") or
               isinstance(n, ast.alias) and n.name == "import_module" for n in ast.walk(tree)):
        return found
    for node in tree.body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, ast.Dict):
            for v in node.value.values:
                first = v.elts[0] if isinstance(v, ast.Tuple) and v.elts else v
                if isinstance(first, ast.Constant) and isinstance(first.value, str) \
                        and first.value.startswith("."):
                    name = first.value.lstrip(".")
                    level = len(first.value) - len(name)
                    target = _known(_absolute(module, level, name or None))
                    assert target, f"{module}: {first.value!r} in a lazy table is no module"
                    found.add(target)
    return found


def import_graph() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """(module-level edges, lazy edges): module -> the modules of the package it imports."""
    eager: dict[str, set[str]] = {m: set() for m in MODULES}
    lazy: dict[str, set[str]] = {m: set() for m in MODULES}

    def walk(module: str, body: list, local: bool) -> None:
        for node in body:
            if _is_type_checking(node):
                walk(module, node.orelse, local)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                (lazy if local else eager)[module] |= _import_targets(module, node) - {module}
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                walk(module, node.body, True)
            else:
                for field in ("body", "orelse", "finalbody", "handlers", "cases"):
                    walk(module, getattr(node, field, None) or [], local)

    for module, path in MODULES.items():
        tree = ast.parse(path.read_text())
        walk(module, tree.body, False)
        lazy[module] |= _lazy_tables(module, tree) - eager[module] - {module}
    return eager, lazy


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


EAGER, LAZY = import_graph()


def _both() -> dict[str, set[str]]:
    return {m: EAGER[m] | LAZY[m] for m in MODULES}


def test_no_import_cycle_between_modules():
    """Module-level and lazy imports together have no cycle."""
    found = cycles(_both())
    assert not found, "import cycles (move the shared piece into a module below both):\n" + \
        "\n".join(" <-> ".join(c) for c in found)


def test_the_cycle_finder_finds_a_cycle_through_a_lazy_import():
    """The checker itself: a package that loads its store lazily, and a store that imports
    a constant back from the package (the shape the cache had), is a cycle."""
    graph = {"cache": {"cache.modes"}, "cache.store": {"cache"}, "cache.modes": set()}
    assert cycles(graph) == []
    graph["cache"].add("cache.store")
    assert cycles(graph) == [["cache", "cache.store"]]


def test_the_graph_reads_lazy_tables_and_skips_type_checking_imports():
    """The cache package loads its store on first use (a lazy edge, from its ``_LAZY``
    table) and names it for type checkers only (no module-level edge)."""
    assert "pytest_flockai.cache.store" in LAZY["pytest_flockai.cache"]
    assert "pytest_flockai.cache.store" not in EAGER["pytest_flockai.cache"]
    assert "pytest_flockai.cache.modes" in EAGER["pytest_flockai.cache.store"]


def _top(module: str) -> str:
    return module.split(".")[1] if "." in module else "__init__"


def test_no_lazy_import_goes_up_the_layers():
    """test_architecture.py checks every import statement; a lazy table is a dict of
    strings it cannot see: the same rule for those."""
    bad = []
    for module, targets in LAZY.items():
        for target in targets:
            a, b = _top(module), _top(target)
            if a != b and (_layer_of(b) > _layer_of(a)
                           or _layer_of(b) == _layer_of(a) and (a, b) not in SAME_LAYER):
                bad.append(f"{module} loads {target} lazily (layer {_layer_of(a)} -> "
                           f"{_layer_of(b)})")
    assert not bad, "\n".join(bad)


def _is_shim(path: Path) -> bool:
    """A module left at an old path: only ``__getattr__ = moved(...)`` (``_deprecation.py``)."""
    return "__getattr__ = moved(" in path.read_text() and not any(
        isinstance(n, (ast.FunctionDef, ast.ClassDef)) for n in ast.parse(path.read_text()).body)


def _concept(name: str) -> str:
    """A file or folder name as a word: ``_device``, ``devices`` -> ``device``."""
    name = name.lstrip("_")
    return name[:-1] if name.endswith("s") and not name.endswith("ss") else name


def names_alike(root: Path) -> dict[str, set[str]]:
    """word -> the modules and packages (``sweeps/runner``, ``reports``) of different homes
    (top-level module or package) whose name is that word."""
    homes: dict[str, dict[str, str]] = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).with_suffix("").parts
        if _is_shim(path):
            continue
        for i, part in enumerate(rel):
            if part != "__init__":
                homes.setdefault(_concept(part), {})["/".join(rel[:i + 1])] = rel[0]
    return {word: set(named) for word, named in homes.items()
            if len(set(named.values())) > 1}


def test_no_two_homes_name_a_module_alike():
    """One word, one thing: a module or package name appears in one home only, unless
    ALIKE says why (a shim left at an old path does not count)."""
    found = names_alike(PKG)
    allowed = {word: set(named) for word, named in ALIKE}
    bad = {w: sorted(n) for w, n in found.items() if allowed.get(w) != n}
    assert not bad, "named alike in different homes (rename one, or say why in ALIKE):\n" + \
        "\n".join(f"{w}: {n}" for w, n in sorted(bad.items()))
    stale = sorted(set(allowed) - set(found))
    assert not stale, f"ALIKE entries no longer needed: {stale}"


def test_the_name_check_finds_a_module_beside_a_package_of_its_name(tmp_path):
    pkg = tmp_path / "pytest_flockai"
    for rel in ("report.py", "reports/__init__.py", "reports/html.py", "world/markers.py",
                "harness/markers.py", "fleet/fleet.py"):
        (pkg / rel).parent.mkdir(parents=True, exist_ok=True)
        (pkg / rel).write_text("")
    assert names_alike(pkg) == {"report": {"report", "reports"},
                     "marker": {"harness/markers", "world/markers"}}


SHIMS = [p for p in MODULES.values() if _is_shim(p)]


@pytest.mark.parametrize("path", SHIMS, ids=lambda p: str(p.relative_to(PKG)))
def test_a_shim_imports_nothing_of_the_package(path):
    """A module left at an old path loads its new home only when a moved name is read, and
    its name is no name its package binds: importing it would bind the module over that
    name (``fa.comm.link`` is a function; a ``comm/link.py`` shim would shadow it)."""
    assert not EAGER[_dotted(path)] - {"pytest_flockai._deprecation"}, EAGER[_dotted(path)]
    init = ast.parse((path.parent / "__init__.py").read_text())
    bound = {a.asname or a.name for n in ast.walk(init) if isinstance(n, ast.ImportFrom)
             for a in n.names} | {t.id for n in init.body if isinstance(n, ast.Assign)
                                  for t in n.targets if isinstance(t, ast.Name)} \
        | {n.name for n in init.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    assert path.stem not in bound, f"{path.parent.name}/__init__.py binds {path.stem!r}"


@pytest.mark.parametrize("path", SHIMS, ids=lambda p: str(p.relative_to(PKG)))
def test_a_module_that_moved_warns_once_with_its_new_home(path):
    """Every name of a module left at an old path is found at its new home; reading one
    through the old path gives that object and warns once, naming the new home."""
    call = next(n.value for n in ast.parse(path.read_text()).body
                if isinstance(n, ast.Assign) and isinstance(n.value, ast.Call))
    names = ast.literal_eval(call.args[1])
    old = importlib.import_module(_dotted(path))
    for new in names.values():
        home, _, attr = new.rpartition(".")
        assert hasattr(importlib.import_module(home), attr), new
    name, new = next(iter(names.items()))
    _deprecation._WARNED.discard((old.__name__, name))
    with pytest.warns(DeprecationWarning, match=re.escape(f"moved to {new};")):
        value = getattr(old, name)
    home, _, attr = new.rpartition(".")
    assert value is getattr(importlib.import_module(home), attr)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert getattr(old, name) is value                   # once: no second warning


def test_the_test_folders_mirror_the_packages():
    """tests/<name>/ holds the tests of pytest_flockai/<name>/ (the conftest's docstring):
    a test folder with no package of its name is a folder that drifted."""
    tests = Path(__file__).resolve().parents[1]
    data = {"golden", "project", "apps", "schemas", "__pycache__"}   # data and repo-wide checks
    packages = {p.parent.name for p in PKG.glob("*/__init__.py")}
    folders = {p.name for p in tests.iterdir() if p.is_dir() and not p.name.startswith(".")}
    assert folders - data <= packages, sorted(folders - data - packages)
    assert len(folders & packages) >= 10
    for f in sorted(folders & packages):
        assert list((tests / f).glob("test_*.py")), f"tests/{f}/ has no test file"
