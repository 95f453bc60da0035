"""MuJoCo for the package's modules, imported once through a GL guard: every
module that needs MuJoCo imports it as ``from .._mujoco import mujoco``, so the
guard runs before MuJoCo's first import, whichever module comes first (the
package itself imports nothing heavy: ``pytest_flockai/__init__.py``)."""

import os
import sys


def _import_mujoco():
    """Import MuJoCo even when ``MUJOCO_GL`` names a GL backend that cannot load.

    MuJoCo loads the backend named by ``MUJOCO_GL`` at import time, and a
    missing library (say OSMesa) breaks the import itself, although physics
    needs no GL at all. Then MuJoCo is imported with GL disabled, the user's
    setting is kept, and the camera reports the problem when it is first used.
    """
    try:
        import mujoco  # noqa: F401
        return None
    except Exception as exc:
        gl = os.environ.get("MUJOCO_GL", "")
        if not gl.strip():
            raise
        for name in [m for m in sys.modules if m.split(".")[0] in ("mujoco", "OpenGL")]:
            del sys.modules[name]
        saved_platform = os.environ.pop("PYOPENGL_PLATFORM", None)
        os.environ["MUJOCO_GL"] = "disable"
        try:
            import mujoco  # noqa: F401,F811
        finally:
            os.environ["MUJOCO_GL"] = gl
            if saved_platform is not None:
                os.environ["PYOPENGL_PLATFORM"] = saved_platform
        return f"MUJOCO_GL={gl!r} could not be loaded: {type(exc).__name__}: {exc}"


GL_IMPORT_ERROR = _import_mujoco()

import mujoco  # noqa: E402

__all__ = ["GL_IMPORT_ERROR", "mujoco"]
