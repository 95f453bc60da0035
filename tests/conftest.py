import os

import pytest

pytest_plugins = ["pytester"]

#: CI's newest-versions stage sets this: a JAX test that skips is then an error
#: (the batched backend's twins must run somewhere; see .ci/run)
REQUIRE_JAX = os.environ.get("FLOCKAI_REQUIRE_JAX") == "1"


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
