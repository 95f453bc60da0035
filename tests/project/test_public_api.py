"""The public face: ``pytest_flockai.__all__`` and the ``__all__`` of each documented
subpackage named in it (``fa.pilots``, ``fa.ml``...) is the whole API. Every docs,
README and example code block imports only those names; each ``__all__`` lists only
names that exist; the API reference lists exactly them; and a name that moved to
another public home keeps working at the old one with one warning naming the new one.

The public set is read from the ``__all__`` lists, never written out here, so a
branch that adds a public name only adds it to an ``__all__`` (and, for a top-level
name, to docs/reference/api.md)."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
import types
import warnings
from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai import _deprecation

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("flockai_docs_gen", ROOT / "docs" / "gen.py")
gen = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen)


def public_modules() -> dict[int, types.ModuleType]:
    """The package and every module reached from it through ``__all__`` (by identity)."""
    found = {id(fa): fa}
    todo = [fa]
    while todo:
        mod = todo.pop()
        for name in mod.__all__:
            obj = getattr(mod, name)
            if isinstance(obj, types.ModuleType) and obj.__name__.startswith("pytest_flockai") \
                    and id(obj) not in found:
                found[id(obj)] = obj
                todo.append(obj)
    return found


PUBLIC = public_modules()


def _public_module(dotted: str) -> types.ModuleType | None:
    """``pytest_flockai.a.b`` when each step is in the ``__all__`` before it (so
    ``pytest_flockai.world.actors`` is public, ``pytest_flockai.control.pilots`` is not)."""
    parts = dotted.split(".")
    if parts[0] != "pytest_flockai":
        return None
    mod = fa
    for part in parts[1:]:
        if part not in mod.__all__ or not isinstance(getattr(mod, part), types.ModuleType):
            return None
        mod = getattr(mod, part)
    return mod


def deep_imports(source: str) -> list[str]:
    """The names of pytest_flockai that ``source`` reaches other than through ``__all__``:
    imports of internal modules, and attribute chains (``fa.ml.evaluation.x``) that step
    outside a public module's ``__all__``."""
    tree = ast.parse(source)
    bad: list[str] = []
    modules: dict[str, types.ModuleType] = {}       # local name -> public module
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if not a.name.startswith("pytest_flockai"):
                    continue
                mod = _public_module(a.name)
                if mod is None:
                    bad.append(f"line {node.lineno}: import {a.name}")
                elif a.asname:
                    modules[a.asname] = mod
                else:
                    modules["pytest_flockai"] = fa
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("pytest_flockai"):
            mod = _public_module(node.module)
            if mod is None:
                bad.append(f"line {node.lineno}: from {node.module} import ...")
                continue
            for a in node.names:
                if a.name not in mod.__all__:
                    bad.append(f"line {node.lineno}: from {node.module} import {a.name}")
                elif isinstance(getattr(mod, a.name), types.ModuleType):
                    modules[a.asname or a.name] = getattr(mod, a.name)
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute) or getattr(node, "_seen", False):
            continue
        chain, value = [], node
        while isinstance(value, ast.Attribute):
            value._seen = True                      # inner nodes of this chain: not again
            chain.append(value.attr)
            value = value.value
        if not isinstance(value, ast.Name) or value.id not in modules:
            continue
        mod, path = modules[value.id], value.id
        for attr in reversed(chain):
            if id(mod) not in PUBLIC:
                break                               # left the package (fst.st is hypothesis')
            path += f".{attr}"
            if attr not in mod.__all__:
                bad.append(f"line {node.lineno}: {path}")
                break
            obj = getattr(mod, attr)
            if not isinstance(obj, types.ModuleType):
                break                               # a class or function: its members are its own
            mod = obj
    return bad


def _code_blocks() -> list[tuple[str, str]]:
    out = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        blocks = re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)
        out += [(f"{page.relative_to(ROOT)} python block {i}", b) for i, b in enumerate(blocks)]
    for path in sorted((ROOT / "example_tests").glob("*.py")):
        out.append((str(path.relative_to(ROOT)), path.read_text()))
    return out


def test_the_checker_finds_deep_imports_and_passes_public_ones():
    deep = ("import pytest_flockai as fa\nfrom pytest_flockai.budgets import check\n"
            "from pytest_flockai.ml import evaluation\nimport pytest_flockai.sweeps.runner\n"
            "from pytest_flockai import strategies as fst\nfrom pytest_flockai.ml import Task\n"
            "fa.ml.envelope.envelope(1, 2)\nfa.sensors.gimbal_pose\nfst.st.floats(0, 1)\n"
            "fa.pilots.Hover(1.0, 2.0).to_dict()\nfrom pytest_flockai.control.pilots import Hover\n"
            "from pytest_flockai.world.actors import Person\nfst.target_margin\n")
    assert set(deep_imports(deep)) == {
        "line 2: from pytest_flockai.budgets import ...",
        "line 3: from pytest_flockai.ml import evaluation",
        "line 4: import pytest_flockai.sweeps.runner",
        "line 11: from pytest_flockai.control.pilots import ...",
        "line 7: fa.ml.envelope", "line 8: fa.sensors.gimbal_pose"}


def test_docs_readme_and_examples_import_only_public_names():
    blocks = _code_blocks()
    assert len(blocks) > 50                         # the pages were found
    bad = [f"{where}: {b}" for where, src in blocks for b in deep_imports(src)]
    assert not bad, "not public (use the name from docs/reference/api.md):\n" + "\n".join(bad)


@pytest.mark.parametrize("mod", list(PUBLIC.values()), ids=lambda m: m.__name__)
def test_every_all_lists_only_names_that_exist_once(mod):
    missing = [n for n in mod.__all__ if not hasattr(mod, n)]
    assert not missing, f"{mod.__name__}.__all__ lists names it lacks: {missing}"
    assert len(set(mod.__all__)) == len(mod.__all__), sorted(mod.__all__)


def _resolve(path: str):
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for part in parts[i:]:
            obj = getattr(obj, part)
        return obj
    raise AssertionError(f"{path} does not resolve")


def test_the_api_reference_lists_exactly_the_public_names():
    text = (ROOT / "docs" / "reference" / "api.md").read_text()
    assert "Anything not listed here is internal and may change" in text
    assert "<!-- gen:api -->" in text
    text = text.replace("<!-- gen:api -->", gen.api())
    top: set[str] = set()
    sections: dict[int, set[str]] = {}
    extra = []
    for path, opts in re.findall(r"^::: (\S+)\n((?:    .*\n?)*)", text, re.M):
        obj = _resolve(path)
        if isinstance(obj, types.ModuleType) and id(obj) in PUBLIC:
            listed = re.search(r"members: \[(.*?)\]", opts)
            assert listed, f"{path}: a subpackage section lists its members"
            sections[id(obj)] = {m.strip() for m in listed.group(1).split(",") if m.strip()}
        elif path.startswith("pytest_flockai.") and path.count(".") == 1 \
                and path.split(".")[1] in fa.__all__:
            top.add(path.split(".")[1])
        else:
            extra.append(path)
    assert not extra, f"api.md documents names that are not public: {extra}"

    def is_module(mod, n):
        return isinstance(getattr(mod, n), types.ModuleType)

    want_top = {n for n in fa.__all__ if not n.startswith("__") and not is_module(fa, n)}
    assert top == want_top, (f"missing from api.md: {sorted(want_top - top)}; "
                             f"listed but not in fa.__all__: {sorted(top - want_top)}")
    want = {id(m): {n for n in m.__all__ if not is_module(m, n)}
            for m in PUBLIC.values() if m is not fa}
    assert sections == want, sorted(PUBLIC[k].__name__ for k in set(sections) ^ set(want))


# the deep imports users have today: they keep working, and give the public object
KEPT = [("pytest_flockai.budgets", "check", "check_budgets"),
        ("pytest_flockai.budgets", "evaluate", "evaluate_budgets"),
        ("pytest_flockai.cache", "FlightCache", "FlightCache"),
        ("pytest_flockai.cache", "caching", "caching"),
        ("pytest_flockai.cache", "cacheable", "cacheable"),
        ("pytest_flockai.ml.evaluation", "detection_kpis", "ml.detection_kpis"),
        ("pytest_flockai.ml.envelope", "envelope", "ml.detection_envelope"),
        ("pytest_flockai.ml.envelope", "altitude_band", "ml.altitude_band"),
        ("pytest_flockai.sweeps.runner", "choose_backend", "sweeps.choose_backend"),
        ("pytest_flockai.compute.devices", "DEVICES", "compute.DEVICES"),
        ("pytest_flockai.reports.compare", "compare", "reports.compare_reports"),
        ("pytest_flockai.reports.compare", "classify", "reports.classify"),
        ("pytest_flockai.reports.scenario", "summary", "reports.scenario_summary")]


@pytest.mark.parametrize("module, name, public", KEPT)
def test_an_old_deep_import_still_gives_the_public_object(module, name, public):
    obj = fa
    for part in public.split("."):
        obj = getattr(obj, part)
    assert getattr(importlib.import_module(module), name) is obj


def test_a_moved_name_warns_once_with_its_new_home():
    from pytest_flockai import sensors, world

    _deprecation._WARNED.discard(("pytest_flockai.sensors", "gimbal_pose"))
    with pytest.warns(DeprecationWarning, match=r"sensors\.gimbal_pose moved to "
                                                r"pytest_flockai\.world\.gimbal_pose"):
        old = sensors.gimbal_pose
    assert old is world.gimbal_pose
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert sensors.gimbal_pose is world.gimbal_pose          # once: no second warning
    assert "gimbal_pose" not in sensors.__all__ and "gimbal_pose" in world.__all__
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        sensors.no_such_name  # noqa: B018
