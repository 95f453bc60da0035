"""Shared test configuration: pytester, and the test groups.

The folders mirror the package: ``tests/<package>/`` tests ``pytest_flockai/<package>/``,
``tests/test_<module>.py`` a top-level module, ``tests/project/`` the repository-wide
checks (layers, public API, docs, README, packaging, the bad-input corpora). Helpers
shared by several folders (``labelled_sets``, ``onnx_nets``, ``sweep_faults``, ``golden/``)
sit here, importable from every folder (this file's folder is on ``sys.path``).

Groups are markers (registered in pyproject.toml), set in the test files themselves
(``pytestmark = pytest.mark.slow`` for a whole file, ``@pytest.mark.slow`` for one test,
``pytest.param(..., marks=pytest.mark.slow)`` for one parametrization), so a renamed test
keeps its group:

- ``slow``: more than a few seconds on an idle 2-core machine (hypothesis searches,
  pytester runs under xdist, flights to battery depletion, JIT compiles, packaging);
  ``pytest tests -m "not slow" -n 2`` is the inner loop.
- ``jax``: needs the ``[mjx]`` extra; CI's newest-versions stage must not skip them:
  with ``FLOCKAI_REQUIRE_JAX=1`` (.ci/run) a skipped ``jax`` test fails, and JAX
  missing is a usage error.
- ``browser``: drives headless Chromium.
"""

import importlib
import os

import pytest

pytest_plugins = ["pytester"]

#: CI's newest-versions stage sets this: a jax test that skips is then a failure
REQUIRE_JAX = os.environ.get("FLOCKAI_REQUIRE_JAX") == "1"

# ``import pytest_flockai`` is lazy (PEP 562), so the first flight of a session may happen
# inside a pytester in-process run; pytester then drops the modules that run imported, and the
# next run imports numpy's C extension a second time ("cannot load module more than once per
# process", or an abort). The C extensions the flights use are imported here, once, first.
for _name in ("numpy", "pandas", "mujoco", "cv2", "onnxruntime", "matplotlib.pyplot",
              "pytest_flockai.mission", "pytest_flockai.ml", "pytest_flockai.fleet",
              "pytest_flockai.sweeps", "pytest_flockai.plots"):
    try:
        if _name == "matplotlib.pyplot":
            importlib.import_module("matplotlib").use("Agg")
        importlib.import_module(_name)
    except ImportError:
        pass


def pytest_sessionstart(session):
    if REQUIRE_JAX:
        try:
            import jax  # noqa: F401
            import mujoco.mjx  # noqa: F401
        except ImportError as exc:
            raise pytest.UsageError(f"FLOCKAI_REQUIRE_JAX=1 but JAX/MJX do not import ({exc}): "
                                    f"the jax-marked tests would skip") from None


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    if REQUIRE_JAX and rep.skipped and item.get_closest_marker("jax") is not None:
        rep.outcome = "failed"
        rep.longrepr = f"FLOCKAI_REQUIRE_JAX=1: a jax-marked test skipped: {rep.longrepr}"
