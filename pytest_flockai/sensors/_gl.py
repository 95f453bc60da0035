"""Headless OpenGL for the rendered camera, chosen lazily on first use.

``mujoco`` picks its default GL backend from ``MUJOCO_GL`` when it is
imported, before any camera exists (and on Linux with ``MUJOCO_GL`` unset it
picks GLFW, which needs a display). So the camera does not rely on that
choice: it imports a backend's ``GLContext`` itself, when the first frame is
rendered:

- ``MUJOCO_GL`` set to ``egl``, ``osmesa`` or ``glfw``: that backend only;
- ``MUJOCO_GL`` unset (or empty): EGL (GPU or Mesa's software rasteriser),
  then OSMesa; the one that works is written back to ``MUJOCO_GL`` so child
  processes make the same choice.

If none works, ``FlockAIError`` says what to install. Code without a camera
never comes here, so it never needs GL.
"""

from __future__ import annotations

import os

from ..errors import FlockAIError

_HINT = {
    "egl": "apt-get install libegl1 libgl1-mesa-dri (Debian/Ubuntu; Mesa's EGL, software "
           "rendering without a GPU)",
    "osmesa": "apt-get install libosmesa6 (Debian/Ubuntu)",
    "glfw": "a display (X11/Wayland) and `pip install glfw`",
}

_backend: str | None = None


def _context_class(name: str):
    if name == "egl":
        from mujoco.egl import GLContext
    elif name == "osmesa":
        from mujoco.osmesa import GLContext
    elif name == "glfw":
        from mujoco.glfw import GLContext
    else:
        raise FlockAIError(f"MUJOCO_GL = {name!r} is not supported by the flockai camera; "
                           f"allowed: 'egl', 'osmesa', 'glfw' or unset")
    return GLContext


def backend() -> str | None:
    """The GL backend in use, or None before the first frame."""
    return _backend


def create_context(width: int, height: int):
    """A current GL context able to render ``width x height`` offscreen."""
    global _backend
    env = os.environ.get("MUJOCO_GL", "").strip().lower()
    if _backend is not None:
        choices = [_backend]
    elif env:
        choices = [env]
    else:
        choices = ["egl", "osmesa"]
    errors = []
    for name in choices:
        saved = os.environ.get("PYOPENGL_PLATFORM")
        try:
            ctx = _context_class(name)(width, height)
            ctx.make_current()
        except FlockAIError:
            raise
        except Exception as exc:   # ImportError, OSError, RuntimeError, EGL/GL errors
            errors.append(f"{name}: {type(exc).__name__}: {exc}")
            if saved is None:
                os.environ.pop("PYOPENGL_PLATFORM", None)
            else:
                os.environ["PYOPENGL_PLATFORM"] = saved
            continue
        _backend = name
        if not env:
            os.environ["MUJOCO_GL"] = name
        return ctx
    install = "; or ".join(_HINT.get(n, n) for n in choices)
    raise FlockAIError("the camera cannot render: no headless OpenGL backend works ("
                       + " | ".join(errors) + f"). Install one: {install}; or set MUJOCO_GL "
                       f"to a backend that works on this machine")
