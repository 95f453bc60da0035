"""The public face: ``pytest_flockai.__all__`` and, in each public module listed there,
its own ``__all__`` (a module in it is public in turn). The docs' code blocks, the
example suite and the API reference use public names only, so anything else can move."""

import ast
import importlib
import re
import types
from pathlib import Path

import pytest

import pytest_flockai as fa

ROOT = Path(__file__).resolve().parent.parent
API = ROOT / "docs" / "reference" / "api.md"


def public_names(module) -> set:
    """A public module's ``__all__``; without one, its names without a leading underscore
    (its submodules included: they load on import)."""
    names = getattr(module, "__all__", None)
    if names is not None:
        return set(names)
    subs = {p.stem for p in Path(module.__file__).parent.glob("*.py")} \
        if module.__file__.endswith("__init__.py") else set()
    return {n for n in set(vars(module)) | subs if not n.startswith("_")}


def resolve(path: str):
    """The object at the dotted public ``path`` (``pytest_flockai.ml.Task``), or an
    AssertionError naming the first step that is not public."""
    parts = path.split(".")
    assert parts[0] == "pytest_flockai", path
    obj = fa
    for i, name in enumerate(parts[1:], 1):
        where = ".".join(parts[:i])
        assert isinstance(obj, types.ModuleType), f"{path}: {where} is not a module"
        assert name in public_names(obj), f"{path}: {name} is not in {where}.__all__"
        try:
            obj = getattr(obj, name)
        except AttributeError:
            obj = importlib.import_module(f"{obj.__name__}.{name}")
    return obj


def _imports(src: str, where: str):
    for node in ast.walk(ast.parse(src)):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("pytest_flockai"):
            for a in node.names:
                yield f"{node.module}.{a.name}", where
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("pytest_flockai"):
                    yield a.name, where


def _uses():
    for page in sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]:
        for i, block in enumerate(re.findall(r"^```python\n(.*?)^```", page.read_text(),
                                             re.S | re.M)):
            yield from _imports(block, f"{page.relative_to(ROOT)} block {i}")
    for path in sorted((ROOT / "example_tests").rglob("*.py")):
        yield from _imports(path.read_text(), str(path.relative_to(ROOT)))


USES = sorted(set(_uses()))


def test_the_docs_and_examples_import_something():
    assert len(USES) > 20 and any(u.startswith("pytest_flockai.budgets.") for u, _ in USES)


@pytest.mark.parametrize("name, where", USES, ids=[f"{w}: {u}" for u, w in USES])
def test_docs_and_examples_import_only_public_names(name, where):
    resolve(name)


def test_an_internal_path_is_not_public():
    for path in ("pytest_flockai.mission.plan.resolve", "pytest_flockai.report.regressions",
                 "pytest_flockai.reports.html", "pytest_flockai.ml.scheduler"):
        with pytest.raises(AssertionError, match="is not in"):
            resolve(path)


def test_every_public_name_resolves():
    for name in fa.__all__:
        if name != "__version__":
            assert getattr(fa, name) is not None


def test_the_api_reference_documents_public_paths_and_every_top_level_name():
    text = API.read_text()
    documented = re.findall(r"^::: (pytest_flockai[\w.]*)", text, re.M)
    for path in documented:
        resolve(path)
    missing = [n for n in fa.__all__ if n != "__version__"
               and not isinstance(getattr(fa, n), types.ModuleType)
               and f"pytest_flockai.{n}" not in documented]
    assert not missing, f"in __all__ but not in docs/reference/api.md: {missing}"
    assert "<!-- gen:public_api -->" in text      # the public modules, generated from __all__
