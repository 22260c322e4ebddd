"""MuJoCo's OpenGL backend on a machine without a display, chosen before ``mujoco`` loads.

MuJoCo picks its GL platform once, when ``mujoco`` is imported, from ``MUJOCO_GL`` (unset:
GLFW, which needs a display). On a headless machine (Linux, ``DISPLAY`` and
``WAYLAND_DISPLAY`` unset) with ``MUJOCO_GL`` unset, importing this module sets
``MUJOCO_GL=egl`` when an EGL library loads (a GPU driver's or Mesa's), else ``osmesa`` when
OSMesa loads, as dm_control and other MuJoCo suites do. A ``MUJOCO_GL`` the user set is never
changed, and ``PYOPENGL_PLATFORM``, when set, limits the choice to the backend it names (MuJoCo
refuses a mismatch). Every package ``__init__`` that can lead to importing ``mujoco``
imports this module first; it imports nothing heavy (``ctypes`` only). docs/envs.md,
"Headless rendering".

``make_renderer`` and ``check_rendering`` turn a failing GL context into one line
(``RenderingError``) that says what to set.
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Callable, Mapping
from typing import Any

HEADLESS_BACKENDS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("egl", ("libEGL.so.1", "libEGL.so")),
    ("osmesa", ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")),
)
"""Headless backends in order of preference, with the shared libraries each one loads."""

GL_HELP = ("set MUJOCO_GL=egl (a GPU driver's or Mesa's libEGL) or MUJOCO_GL=osmesa (libOSMesa) "
           "before Python starts; docs/envs.md, 'Headless rendering'")
"""What to do when no GL context can be made."""

chosen: str | None = None
"""The backend this module set (None: ``MUJOCO_GL`` was left as it was)."""


def has_display(environ: Mapping[str, str]) -> bool:
    """Whether an X11 or Wayland display is named in ``environ``."""
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def library_loads(names: tuple[str, ...]) -> bool:
    """Whether one of the shared libraries ``names`` can be loaded (dlopen)."""
    for name in names:
        try:
            ctypes.CDLL(name)
        except OSError:
            continue
        return True
    return False


def choose_backend(environ: Mapping[str, str], platform: str,
                   loads: Callable[[tuple[str, ...]], bool] = library_loads) -> str | None:
    """The headless backend to set, or None to leave ``MUJOCO_GL`` alone (it is set, there is
    a display, the OS is not Linux, or no headless library loads)."""
    if environ.get("MUJOCO_GL", "").strip() or not platform.startswith("linux"):
        return None
    if has_display(environ):
        return None
    pyopengl = environ.get("PYOPENGL_PLATFORM", "").strip().lower()
    for backend, libraries in HEADLESS_BACKENDS:
        if pyopengl and pyopengl != backend:
            continue
        if loads(libraries):
            return backend
    return None


def select_headless_backend() -> str | None:
    """Set ``MUJOCO_GL`` to the headless backend ``choose_backend`` picks (once, and only if
    ``mujoco`` is not imported yet: afterwards the choice has no effect). Returns it."""
    global chosen
    if chosen is None and "mujoco" not in sys.modules:
        chosen = choose_backend(os.environ, sys.platform, library_loads)
        if chosen is not None:
            os.environ["MUJOCO_GL"] = chosen
    return chosen


def _rendering_error(reason: str) -> Exception:
    from impact_control.errors import RenderingError as Error

    gl = os.environ.get("MUJOCO_GL") or "unset"
    display = "a display" if has_display(os.environ) else "no display"
    late = (" (mujoco was imported before impact_envs, too late to pick one)"
            if chosen is None and gl == "unset" and display == "no display" else "")
    return Error(f"cannot render with MuJoCo (MUJOCO_GL={gl}, {display}{late}): "
                 f"{' '.join(reason.split())[:200]}; {GL_HELP}")


def make_renderer(model: Any, height: int, width: int) -> Any:
    """``mujoco.Renderer(model, height, width)``, a failing GL context as ``RenderingError``."""
    import mujoco

    try:
        return mujoco.Renderer(model, height=height, width=width)
    except ValueError:
        raise  # a size beyond the scene's offscreen buffer: the caller's argument, not GL
    except Exception as exc:  # noqa: BLE001 - FatalError, ImportError, AttributeError of PyOpenGL
        raise _rendering_error(f"{type(exc).__name__}: {exc}") from None


_probed: str | None = None
"""The ``MUJOCO_GL`` value ``check_rendering`` last succeeded with."""


def check_rendering() -> None:
    """Make and close one tiny offscreen renderer, so that a run which will render (``--video``)
    fails in one line before it writes anything. Cached per ``MUJOCO_GL`` value."""
    global _probed
    gl = os.environ.get("MUJOCO_GL", "")
    if _probed == gl:
        return
    import mujoco

    model = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><geom size='0.1'/></worldbody></mujoco>")
    renderer = make_renderer(model, 8, 8)
    try:
        renderer.update_scene(mujoco.MjData(model))
        renderer.render()
    except Exception as exc:  # noqa: BLE001 - any failure to draw is the same one line
        raise _rendering_error(f"{type(exc).__name__}: {exc}") from None
    finally:
        renderer.close()
    _probed = gl


select_headless_backend()
