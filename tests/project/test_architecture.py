"""The package's layers, enforced: each module imports only from its own layer
or the layers below it, the core never imports pytest, and imports sit at
module level (a function-level import is allowed only for an optional
dependency or a platform backend). Within a layer, a package may import another
only where SAME_LAYER says so. LAYERS is data, in
pytest_flockai/_layers.py; the docs' architecture page prints it (docs/gen.py)."""

import ast
import re
from pathlib import Path

import pytest

from pytest_flockai._layers import LAYERS as _LAYERS

PKG = Path(__file__).resolve().parents[2] / "pytest_flockai"

LAYERS = list(_LAYERS)
PYTEST_SIDE = LAYERS[-1] - {"plots", "cli", "__main__", "__init__", "sweeps"}
#: function-level imports that are fine: optional extras (dask and distributed: the
#: "dask" extra; openvino, ncnn and LiteRT: profile-device's runtimes), GL backends
#: loaded on demand, and scipy.stats (a dependency, but ~1 s to import: only the Latin-hypercube design needs it)
OPTIONAL = {"matplotlib", "pyarrow", "pyinstrument", "torch", "pytest_html", "albumentations",
            "mujoco.egl", "mujoco.osmesa", "mujoco.glfw", "scipy.stats", "distributed", "dask",
            "openvino", "ai_edge_litert", "tflite_runtime", "tensorflow", "ncnn"}
#: the import-time MuJoCo/GL guard (``_mujoco.py``, see its docstring), and the
#: sweep runner loading the batched backend, whose modules import JAX (the optional
#: extra ``mjx``), only when ``backend="mjx"`` is asked for
# shards.py asks JAX only after it set the XLA flags for the host devices (read at client start)
ALLOWED_LOCAL = {("_mujoco.py", "mujoco"), ("sweeps/runner.py", ".batched"),
                 ("sweeps/batched/shards.py", "jax")}
#: loaded on first use, so that the pytest plugin costs a run that flies nothing almost
#: nothing (``benchmarks/plugin_overhead.py``): (module, imported from, name) -> why.
#: The core behind the fixtures (MuJoCo, ONNX Runtime, pandas), the sweep runner and
#: envelope behind a sweep's hooks, and the plots (NumPy, matplotlib) behind artifacts.
LAZY_LOADS = {
    ("harness/fixtures.py", "..airframe", "drone"): "the drone fixture: the core",
    ("harness/fixtures.py", "..control.pilots", "Hover"): "the pilot fixture: the core",
    ("harness/fixtures.py", "..mission", "Mission"): "the mission fixture: the core",
    ("harness/fixtures.py", "..app.launch", "marker_flight"): "the flockai_app marker: the "
                                                             "MAVLink front-end (pymavlink)",
    ("harness/sweeps.py", "..sweeps", "runner"): "the flockai_sweep fixture: the core",
    ("harness/sweeps.py", "..sweeps", "executors"): "--flockai-sweep-executor given: the core",
    ("harness/sweeps.py", "..sweeps", "envelope_files"): "after a sweep flew (loaded then)",
    ("harness/recorder.py", "..sweeps", "envelope_files"): "after a sweep flew (loaded then)",
    ("reports/files.py", "..", "plots"): "pictures of --flockai-artifacts: NumPy, matplotlib",
    ("harness/ci_reports.py", "..", "plots"): "pictures of the HTML report: NumPy, matplotlib",
    ("cache/key.py", "onnx", "load"): "an ONNX model's external-data files, keyed (0.2 s import)",
}
#: imports between two different names of one layer (importer, imported): each is a
#: decision, so a new one fails until it is added here
SAME_LAYER = {
    ("_check", "errors"), ("_io", "errors"), ("kpis", "errors"), ("limits", "errors"),
    ("recording", "errors"),
    ("result", "_io"), ("result", "errors"), ("result", "phases"), ("result", "notebook"),
    ("notebook", "kpis"),
    ("ml", "control"),
    ("fleet", "cache"), ("fleet", "mission"), ("fleet", "policy"), ("mission", "cache"),
    ("mission", "policy"),
    ("__init__", "sweeps"), ("__init__", "budgets"), ("__init__", "cli"), ("__init__", "plots"),
    ("__init__", "reports"), ("__init__", "strategies"), ("__main__", "cli"), ("budgets", "reports"),
    ("cli", "reports"), ("harness", "budgets"), ("harness", "plots"),
    ("harness", "reports"), ("harness", "sweeps"), ("plugin", "harness"), ("plugin", "hookspecs"),
    ("reports", "plots"), ("strategies", "budgets"), ("sweeps", "budgets"),
    ("sweeps", "plots"),
}


def _layer_of(name: str) -> int:
    for i, layer in enumerate(LAYERS):
        if name in layer:
            return i
    raise AssertionError(f"pytest_flockai.{name} is in no layer: add it to LAYERS in "
                         f"pytest_flockai/_layers.py")


def _modules():
    return sorted(p for p in PKG.rglob("*.py"))


def _top(path: Path) -> str:
    rel = path.relative_to(PKG).parts
    return rel[0][:-3] if len(rel) == 1 else rel[0]


def _targets(path: Path, node) -> list[str]:
    """Top-level pytest_flockai names an import statement reaches."""
    rel = path.relative_to(PKG)
    pkg_parts = list(rel.parts[:-1])
    if isinstance(node, ast.Import):
        return [a.name.split(".")[1] for a in node.names
                if a.name.startswith("pytest_flockai.")]
    if node.level == 0:
        mod = node.module or ""
        if not mod.startswith("pytest_flockai"):
            return []
        parts = mod.split(".")[1:]
    else:
        base = pkg_parts[:len(pkg_parts) - (node.level - 1)] if node.level > 1 else pkg_parts
        parts = base + (node.module.split(".") if node.module else [])
    if parts:
        return [parts[0]]
    return [a.name for a in node.names]          # from . import x


def _layer_violations(path: Path, tree) -> list[str]:
    own = _layer_of(_top(path))
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            for target in _targets(path, node):
                if target != _top(path) and _layer_of(target) > own:
                    bad.append(f"line {node.lineno}: {_top(path)} (layer {own}) imports "
                               f"{target} (layer {_layer_of(target)})")
                elif target != _top(path) and _layer_of(target) == own \
                        and (_top(path), target) not in SAME_LAYER:
                    bad.append(f"line {node.lineno}: {_top(path)} imports {target} of its own "
                               f"layer {own}: not in SAME_LAYER (tests/project/test_architecture.py)")
    return bad


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PKG)))
def test_imports_go_down_the_layers(path):
    bad = _layer_violations(path, ast.parse(path.read_text()))
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PKG)))
def test_no_function_level_imports_and_no_pytest_in_the_core(path):
    rel = str(path.relative_to(PKG))
    tree = ast.parse(path.read_text())
    bad = []
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for node in ast.walk(fn):
                if isinstance(node, ast.Import):
                    names = [(a.name, None) for a in node.names]
                elif isinstance(node, ast.ImportFrom):
                    names = [("." * node.level + (node.module or ""), a.name) for a in node.names]
                else:
                    continue
                for n, name in names:
                    if n not in OPTIONAL and n.split(".")[0] not in OPTIONAL \
                            and (rel, n) not in ALLOWED_LOCAL and (rel, n, name) not in LAZY_LOADS:
                        bad.append(f"line {node.lineno}: {n} imported inside {fn.name}()")
    if _top(path) not in PYTEST_SIDE:
        for node in ast.walk(tree):
            if isinstance(node, ast.Import) and any(a.name.split(".")[0] in ("pytest", "_pytest")
                                                    for a in node.names):
                bad.append(f"line {node.lineno}: the core imports pytest")
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in (
                    "pytest", "_pytest") and node.level == 0:
                bad.append(f"line {node.lineno}: the core imports pytest")
    assert not bad, "\n".join(bad)


def test_lazy_loads_name_one_import_each_and_each_is_still_there():
    """The lazy-load allow-list stays narrow: every entry names one module and one
    imported name, and each is still imported inside a function of that module."""
    for (rel, module, name), why in LAZY_LOADS.items():
        tree = ast.parse((PKG / rel).read_text())
        found = [node for fn in ast.walk(tree) if isinstance(fn, ast.FunctionDef)
                 for node in ast.walk(fn) if isinstance(node, ast.ImportFrom)
                 and "." * node.level + (node.module or "") == module
                 and any(a.name == name for a in node.names)]
        assert found and why, (rel, module, name)


def test_layer_checker_catches_an_upward_import(tmp_path):
    """The checker itself: an energy module importing the mission is reported."""
    fake = PKG / "energy" / "components.py"
    node = ast.parse("from ..mission import Mission").body[0]
    assert _targets(fake, node) == ["mission"]
    assert _layer_of("mission") > _layer_of("energy")
    node = ast.parse("from . import kpis").body[0]
    assert _targets(PKG / "budgets.py", node) == ["kpis"]


def test_same_layer_checker_catches_an_unlisted_import():
    """A layer-0 module importing another one not in SAME_LAYER is reported."""
    assert _layer_violations(PKG / "kpis.py", ast.parse("from .errors import ConfigError")) == []
    bad = _layer_violations(PKG / "kpis.py", ast.parse("from .phases import PHASES"))
    assert len(bad) == 1 and "not in SAME_LAYER" in bad[0]


#: "issue" or "session" and a number: when something changed, which is the CHANGELOG's job
HISTORY = re.compile(r"\b(?:[Ii]ssue|[Ss]ession)\s+#?\d+")
TEXT = {".py", ".toml", ".md", ".txt", ".xsd", ".cfg", ".ini", ".yml", ".yaml", ".json", ".csv"}


def _history_mentions(root: Path) -> list[str]:
    return [f"{path.relative_to(root.parent)}:{n}: {line.strip()}"
            for path in sorted(root.rglob("*")) if path.suffix in TEXT and "__pycache__" not in path.parts
            for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
            if HISTORY.search(line)]


@pytest.mark.parametrize("root", [PKG, PKG.parent / "tests"], ids=["pytest_flockai", "tests"])
def test_comments_say_why_not_when(root):
    """A comment or docstring gives the reason for the code (with its source); when and in
    which ticket it changed is history, kept in CHANGELOG.md. A ticket number in the code
    tells the next reader nothing they can check."""
    bad = _history_mentions(root)
    assert not bad, "history in the code (move it to CHANGELOG.md):\n" + "\n".join(bad)


def test_the_history_check_catches_a_ticket_number(tmp_path):
    n = 14      # the number is joined at run time, so this file does not trip its own check
    (tmp_path / "m.py").write_text(f'"""Fleets (issue {n}): ..."""\n# until Session {n} ...\nx = 1\n')
    assert len(_history_mentions(tmp_path)) == 2


@pytest.mark.parametrize("package", ["harness", "reports"])
def test_package_docstrings_list_exactly_their_modules(package):
    """The package docstrings of harness/ and reports/ are their table of contents: every
    module named there exists, and every module is named (a moved module leaves no stale line)."""
    doc = ast.get_docstring(ast.parse((PKG / package / "__init__.py").read_text())) or ""
    named = set(re.findall(r"``(\w+)``", doc)) & {p.stem for p in (PKG / package).glob("*.py")} \
        | set(re.findall(r"^- ``(\w+)``", doc, flags=re.M))
    modules = {p.stem for p in (PKG / package).glob("*.py")} - {"__init__"}
    assert named == modules, (f"in the docstring only: {sorted(named - modules)}; "
                              f"not in it: {sorted(modules - named)}")


#: the most lines a module of the package may have
MAX_MODULE_LINES = 400


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(PKG)))
def test_every_module_fits_in_400_lines(path):
    """A module is one concept a reader can hold at once: at most 400 lines (about four
    screens at the 100-column limit ruff enforces). A module that outgrows it is two
    concepts: split it by concept (as ``mission/`` was split into plan, assemble, loop and
    collect), rather than squeezing lines. The cap is why ``ruff format`` is not run: its
    one-argument-per-line layout pushes 26 of the modules over 400 lines (measured on a
    copy of the package with ``ruff format --line-length 100``)."""
    n = len(path.read_text().splitlines())
    assert n <= MAX_MODULE_LINES, (f"{path.relative_to(PKG.parent)} has {n} lines; at most "
                                   f"{MAX_MODULE_LINES}: split it by concept")


def test_mission_and_fleet_share_one_run_path():
    """The cache lookup, the flight, the store and the publish are written once
    (mission/sortie.py); Mission.run and Fleet.run hand it only what they build."""
    calls = {}
    for path in [*(PKG / "mission").glob("*.py"), *(PKG / "fleet").glob("*.py")]:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                    and node.func.attr in ("fly", "lookup", "store") \
                    or isinstance(node, ast.Call) and getattr(node.func, "id", "") == "publish":
                calls.setdefault(path.relative_to(PKG).as_posix(), set()).add(
                    getattr(node.func, "attr", getattr(node.func, "id", "")))
    assert calls == {"mission/sortie.py": {"fly", "lookup", "store", "publish"}}
    for rel, cls in (("mission/mission.py", "Mission"), ("fleet/fleet.py", "Fleet")):
        run = next(f for n in ast.parse((PKG / rel).read_text()).body
                   if isinstance(n, ast.ClassDef) and n.name == cls
                   for f in n.body if isinstance(f, ast.FunctionDef) and f.name == "run")
        assert "sortie.run(" in ast.unparse(run), rel
