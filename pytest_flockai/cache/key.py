"""The cache key of a flight: a SHA-256 over everything that shapes it.

The key walks the Mission itself, not its ``scenario()`` summary: every
attribute of the drone (blueprint values and the blueprint file's bytes), the
pilot, the world (its arrays too), the tasks (the model file's bytes for ONNX
models, and the bytes of every external-data file its initializers name by
``location``, e.g. ``weights.bin``), sensors (a replayed folder's images and labels by
their bytes: every string or path naming a file is keyed by the file's SHA-256), any
``side_files`` an object lists (paths of files it reads besides its own), probes,
wind, conditions, seed, ``until`` and every rate and limit of the mission, plus the environment that flies it: the package version
and a hash of the package's own source files, and the versions of Python,
NumPy, MuJoCo, ONNX Runtime, OpenCV and pycocotools (the detection KPIs).

Objects are keyed by their class and their attributes, recursively. A flight
that runs code of yours (your functions, a ``PythonModel`` around a lambda, a
``Pilot`` or ``Probe`` subclass) bypasses the cache, since the cache cannot
replay what that code does besides returning values (a test that counts the
frames its model saw would see none). Mark such code ``cacheable(...)`` when
it has no such effects: it is then keyed by its state *and the bytes of the
file that defines it*, a function also by its closure values and defaults.
What else makes the flight bypass the cache (``Uncacheable`` says why): your
own clocked components (``Mission(components=...)``, they act on the run at
every tick), live subscribers, a dataset recorder (it writes files), objects
of third-party classes the key knows nothing about, and marked functions
whose file cannot be read (defined in a notebook cell or ``python -c``).

A change the key cannot see: code your marked function calls in *another*
file of yours. Clear the cache then (``--flockai-cache-clear``).
"""

from __future__ import annotations

import ast
import dataclasses
import enum
import functools
import hashlib
import inspect
import json
import os
import platform
import sys
import textwrap
import types
from importlib import metadata
from pathlib import Path, PurePath
from typing import Any, TypeVar

import numpy as np

from .._io import file_digest

T = TypeVar("T")

_PKG = "pytest_flockai"
_PKG_DIR = Path(__file__).resolve().parent.parent

#: attributes that are derived from others already in the key (caches, compiled
#: forms): leaving them out keeps a key stable whether or not they were filled.
#: Attributes a class sets in its ``bind*`` methods (per-flight state: the MuJoCo
#: model and data, a sensor's Generator, precomputed rotor terms) are left out too,
#: found from the source (``_bound_attributes``).
_DERIVED = {"session", "_proto", "_mac_cache", "mac_report", "_ready", "_objects", "_objects_key",
            "_meshes", "_meshes_n"}
#: third-party objects held by the package's own classes: runtime handles derived
#: from keyed data (an ONNX Runtime session, a MuJoCo renderer bound for a flight)
_SKIP_MODULES = ("onnxruntime", "mujoco")
#: third-party callables whose behaviour is pinned by their package version
_LIB_MODULES = ("numpy", "cv2", "math", "builtins", "operator", "statistics", "scipy")


class Uncacheable(Exception):
    """This flight cannot be keyed; the message says what (the flight is flown)."""


def environment() -> dict:
    """The versions that shape a flight, computed once per process."""
    return _environment()


@functools.lru_cache(maxsize=1)
def _environment() -> dict:
    versions: dict[str, str | None] = {}
    for dist in ("pytest-flockai", "mujoco", "onnxruntime", "opencv-python-headless", "numpy",
                 "pycocotools"):                  # pycocotools: the detection KPIs
        try:
            versions[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            versions[dist] = None
    return {"python": platform.python_version(), "versions": versions,
            "source": source_hash()}


@functools.lru_cache(maxsize=1)
def source_hash() -> str:
    """SHA-256 of the package's own files (.py and blueprints): an edited
    checkout keys differently from the released version of the same number."""
    h = hashlib.sha256()
    for p in sorted(_PKG_DIR.rglob("*")):
        if p.suffix in (".py", ".toml") and p.is_file() and "__pycache__" not in p.parts:
            h.update(str(p.relative_to(_PKG_DIR)).encode())
            h.update(p.read_bytes())
    return h.hexdigest()


def flight_key(mission: object, env: dict | None = None) -> str:
    """The hex key of ``mission`` (a Mission, or a Fleet: its drones' missions and
    its own settings); raises Uncacheable when it cannot be keyed."""
    for m in getattr(mission, "missions", None) or [mission]:
        if getattr(m, "components", None):
            names = ", ".join(type(c).__name__ for c in m.components)
            raise Uncacheable(f"the mission has components of its own ({names})")
        if getattr(m, "subscribers", None):
            raise Uncacheable("the mission has live subscribers (Mission.subscribe)")
        if getattr(m, "dataset_dir", None) is not None:
            raise Uncacheable("the mission records a dataset (dataset_dir), which writes files")
    doc = {"mission": _Walker().walk(mission, "mission"),
           "environment": env if env is not None else environment()}
    text = json.dumps(doc, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def memo_key(kind: str, inputs: object, env: dict | None = None) -> str:
    """The hex key of a memoised computation (``pytest_flockai.memo``): its kind, its
    inputs walked as a flight's are, and the environment; raises Uncacheable."""
    doc = {"memo": kind, "inputs": _Walker().walk(inputs, kind),
           "environment": env if env is not None else environment()}
    text = json.dumps(doc, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _own(module: str | None) -> bool:
    return module is not None and (module == _PKG or module.startswith(_PKG + "."))


@functools.lru_cache(maxsize=1024)
def _library(module: str | None) -> bool:
    """A module of the standard library or an installed package (not your code)."""
    if not module:
        return False
    top = module.split(".")[0]
    if top in sys.stdlib_module_names or top in sys.builtin_module_names:
        return True
    f = getattr(sys.modules.get(module), "__file__", None) or ""
    return any(part in ("site-packages", "dist-packages") for part in Path(f).parts)


def _defining_file(obj, where: str) -> str:
    mod = sys.modules.get(getattr(obj, "__module__", None) or "")
    code = getattr(obj, "__code__", None)
    fname = code.co_filename if code is not None else getattr(mod, "__file__", None)
    if not fname or not os.path.isfile(fname):
        raise Uncacheable(f"{where}: {getattr(obj, '__qualname__', obj)!r} is defined outside a "
                          f"readable file ({fname or 'no file'}), so its code cannot be keyed")
    return file_digest(fname)


def cacheable(obj: T) -> T:
    """Mark your function or class as safe to cache: its flights depend only on its
    code (the file that defines it is keyed), its state and its closure, and the
    test observes nothing it does besides what the flight returns. Returns ``obj``
    (use it as a decorator, or around a lambda)."""
    marked: Any = obj               # a function, a class or an instance: any object
    marked.__flockai_cacheable__ = True
    return obj


def _require_cacheable(obj, where: str) -> None:
    if not getattr(obj, "__flockai_cacheable__", False):
        raise Uncacheable(f"{where}: {getattr(obj, '__qualname__', obj)!r} is your code, which "
                          f"may do things the cache cannot replay (mark it with "
                          f"pytest_flockai.cache.cacheable if it does not)")


class _Walker:
    """Turns an object graph into plain JSON data (raises Uncacheable)."""

    def __init__(self):
        self.stack: set[int] = set()

    def walk(self, obj, where: str):
        if isinstance(obj, str):
            return self._string(obj)
        if obj is None or isinstance(obj, (bool, int)):
            return obj
        if isinstance(obj, float):
            return {"f": repr(obj)}
        if isinstance(obj, (bytes, bytearray)):
            return {"bytes": hashlib.sha256(bytes(obj)).hexdigest()}
        if isinstance(obj, np.generic):
            return {"np": str(obj.dtype), "v": repr(obj.item())}
        if isinstance(obj, np.ndarray):
            return self._array(obj, where)
        if isinstance(obj, PurePath):
            return self._path(obj)
        if isinstance(obj, types.ModuleType):
            return {"module": obj.__name__}
        if isinstance(obj, enum.Enum):
            return {"enum": f"{type(obj).__module__}.{type(obj).__qualname__}.{obj.name}"}
        if id(obj) in self.stack:
            return {"cycle": type(obj).__qualname__}
        self.stack.add(id(obj))
        try:
            return self._compound(obj, where)
        finally:
            self.stack.discard(id(obj))

    def _array(self, a: np.ndarray, where: str):
        if a.dtype == object:
            return {"objarray": [self.walk(x, f"{where}[]") for x in a.ravel().tolist()],
                    "shape": list(a.shape)}
        return {"array": str(a.dtype), "shape": list(a.shape),
                "sha": hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()}

    @staticmethod
    def _string(s: str):
        """A string; one naming an existing file (a model, a blueprint) brings its bytes
        (an ONNX model's external-data files too)."""
        if len(s) < 4096 and ("/" in s or "." in s) and "\0" not in s:
            try:
                if os.path.isfile(s):
                    return {"str": s, "sha": file_digest(s), **_side(s)}
            except (OSError, ValueError):
                pass
        return s

    @staticmethod
    def _path(p: PurePath):
        out = {"path": str(p)}
        if os.path.isfile(p):
            out["sha"] = file_digest(p)
            out.update(_side(os.fspath(p)))
        return out

    def _compound(self, obj, where: str):
        if isinstance(obj, (list, tuple)):
            return [self.walk(x, f"{where}[{i}]") for i, x in enumerate(obj)]
        if isinstance(obj, (set, frozenset)):
            items = [self.walk(x, f"{where}{{}}") for x in obj]
            return {"set": sorted(json.dumps(i, sort_keys=True) for i in items)}
        if isinstance(obj, dict):
            return {"dict": sorted(([json.dumps(self.walk(k, where), sort_keys=True),
                                     self.walk(v, f"{where}[{k!r}]")] for k, v in obj.items()),
                                   key=lambda kv: kv[0])}
        if isinstance(obj, functools.partial):
            return {"partial": [self.walk(obj.func, where), self.walk(list(obj.args), where),
                                self.walk(dict(obj.keywords), where)]}
        if isinstance(obj, types.FunctionType):
            return self._function(obj, where)
        if isinstance(obj, types.MethodType):
            return {"method": obj.__func__.__qualname__,
                    "self": self.walk(obj.__self__, f"{where}.__self__"),
                    "func": self.walk(obj.__func__, where)}
        if isinstance(obj, (types.BuiltinFunctionType, np.ufunc)):
            mod = getattr(obj, "__module__", None) or "builtins"
            if mod.split(".")[0] not in _LIB_MODULES:
                raise Uncacheable(f"{where}: built-in {obj!r} from {mod} cannot be keyed")
            return {"builtin": f"{mod}.{getattr(obj, '__qualname__', obj.__name__)}"}
        if isinstance(obj, np.random.Generator):
            return {"rng": self.walk(obj.bit_generator.state, where)}
        if isinstance(obj, type):
            return self._class(obj, where)
        return self._object(obj, where)

    def _function(self, fn, where: str):
        out = {"function": f"{fn.__module__}.{fn.__qualname__}"}
        if _own(fn.__module__) or _library(fn.__module__):
            return out
        _require_cacheable(fn, where)
        out["file"] = _defining_file(fn, where)
        out["code"] = hashlib.sha256(fn.__code__.co_code).hexdigest()
        cells = [c.cell_contents for c in (fn.__closure__ or ())]
        out["closure"] = self.walk(cells, f"{where} (closure of {fn.__qualname__})")
        out["defaults"] = self.walk(list(fn.__defaults__ or ()), where)
        out["kwdefaults"] = self.walk(dict(fn.__kwdefaults__ or {}), where)
        return out

    def _class(self, cls: type, where: str):
        out = {"class": f"{cls.__module__}.{cls.__qualname__}"}
        if not _own(cls.__module__) and not _library(cls.__module__):
            _require_cacheable(cls, where)
            out["file"] = _defining_file(cls, where)
        return out

    def _object(self, obj, where: str):
        cls: type = type(obj)
        mod = cls.__module__ or ""
        if mod.split(".")[0] in _SKIP_MODULES:
            return {"skipped": f"{mod}.{cls.__qualname__}"}
        if mod.split(".")[0] == "onnx" and hasattr(obj, "SerializeToString"):
            return {"onnx": hashlib.sha256(obj.SerializeToString()).hexdigest()}
        state = _state(obj)
        if state is None:
            raise Uncacheable(f"{where}: {mod}.{cls.__qualname__} object {_short(obj)} cannot be "
                              f"keyed")
        out = self._class(cls, where)
        side = getattr(obj, "side_files", None)
        if side is not None and not callable(side):
            out["side_files"] = [self._path(Path(os.fspath(f))) for f in side]
        skip = _DERIVED | _bound_attributes(cls)
        out["state"] = {k: self.walk(v, f"{where}.{k}") for k, v in sorted(state.items())
                        if k not in skip}
        return out


def _side(path: str) -> dict:
    """``{"external": {location: sha}}`` for an ONNX model whose initializers keep their
    data in other files (``location``, relative to the model's folder); {} otherwise."""
    if not path.lower().endswith(".onnx"):
        return {}
    st = os.stat(path)
    folder = os.path.dirname(os.path.abspath(path))
    out = {}
    for loc in _external_locations(path, st.st_ino, st.st_mtime_ns, st.st_ctime_ns, st.st_size):
        f = os.path.join(folder, loc)
        out[loc] = file_digest(f) if os.path.isfile(f) else None
    return {"external": out} if out else {}


@functools.lru_cache(maxsize=64)
def _external_locations(path: str, *stamp: int) -> tuple[str, ...]:
    """The ``location`` of every external-data tensor of an ONNX file (initializers of
    the graph and its subgraphs, sparse ones and node attributes), read without the data."""
    try:
        from onnx import load
        model = load(path, load_external_data=False)
    except Exception:  # noqa: BLE001 (not an ONNX file: its own bytes key it)
        return ()
    found: set[str] = set()

    def tensors(graph):
        yield from graph.initializer
        for sp in graph.sparse_initializer:
            yield sp.values
            yield sp.indices
        for node in graph.node:
            for attr in node.attribute:
                if attr.HasField("t"):
                    yield attr.t
                yield from attr.tensors
                subs = ([attr.g] if attr.HasField("g") else []) + list(attr.graphs)
                for g in subs:
                    yield from tensors(g)

    for t in tensors(model.graph):
        if t.data_location == t.EXTERNAL:
            found.update(e.value for e in t.external_data if e.key == "location")
    return tuple(sorted(found))


@functools.lru_cache(maxsize=512)
def _bound_attributes(cls: type) -> frozenset:
    """Names a class (or a base) assigns on ``self`` inside its ``bind*`` methods:
    the state one flight binds and the next one binds again."""
    names: set = set()
    for klass in cls.__mro__:
        for attr, fn in vars(klass).items():
            if not (attr.startswith("bind") and isinstance(fn, types.FunctionType)):
                continue
            try:
                tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
            except (OSError, TypeError, SyntaxError):
                continue
            for node in ast.walk(tree):
                if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) \
                        and isinstance(node.value, ast.Name) and node.value.id == "self":
                    names.add(node.attr)
    return frozenset(names)


def _state(obj) -> dict | None:
    """The attributes of an object of a Python class (None for anything else)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)
                if hasattr(obj, f.name)} | dict(getattr(obj, "__dict__", {}))
    state = {}
    d = getattr(obj, "__dict__", None)
    slots = [s for c in type(obj).__mro__ for s in getattr(c, "__slots__", ())]
    if d is None and not slots:
        return None
    if d is not None:
        state.update(d)
    for s in slots:
        if s not in ("__dict__", "__weakref__") and hasattr(obj, s):
            state[s] = getattr(obj, s)
    mod = type(obj).__module__ or ""
    if not _own(mod) and mod.split(".")[0] in ("mujoco", "cv2", "pandas", "onnxruntime"):
        return None
    return state


def _short(obj) -> str:
    r = repr(obj)
    return r if len(r) <= 60 else r[:57] + "..."
