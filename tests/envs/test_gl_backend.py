"""Headless rendering: with no display and MUJOCO_GL unset, importing any IMPACT package picks
MuJoCo's headless GL backend before mujoco loads (``impact_envs/_gl.py``); a user's MUJOCO_GL
is never changed; a machine that cannot render fails in one line (``RenderingError``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from impact_envs._gl import choose_backend

ROOT = Path(__file__).resolve().parents[2]


def _loads(*available: str):
    """A fake ``library_loads``: these backends' libraries load, no other."""
    libraries = {"egl": "libEGL.so.1", "osmesa": "libOSMesa.so.8"}
    return lambda names: any(libraries[b] in names for b in available)


# name: (environ, platform, backends whose libraries load, expected choice)
CHOICES = {
    "headless linux, egl loads": ({}, "linux", ("egl", "osmesa"), "egl"),
    "headless linux, only osmesa loads": ({}, "linux", ("osmesa",), "osmesa"),
    "headless linux, nothing loads": ({}, "linux", (), None),
    "user set egl": ({"MUJOCO_GL": "egl"}, "linux", ("egl",), None),
    "user set osmesa": ({"MUJOCO_GL": "osmesa"}, "linux", ("egl", "osmesa"), None),
    "user set glfw": ({"MUJOCO_GL": "glfw"}, "linux", ("egl",), None),
    "empty MUJOCO_GL counts as unset": ({"MUJOCO_GL": " "}, "linux", ("egl",), "egl"),
    "X11 display": ({"DISPLAY": ":0"}, "linux", ("egl",), None),
    "Wayland display": ({"WAYLAND_DISPLAY": "wayland-0"}, "linux", ("egl",), None),
    "empty DISPLAY is no display": ({"DISPLAY": ""}, "linux", ("egl",), "egl"),
    "macOS": ({}, "darwin", ("egl",), None),
    "Windows": ({}, "win32", ("egl",), None),
    "PYOPENGL_PLATFORM osmesa": ({"PYOPENGL_PLATFORM": "osmesa"}, "linux", ("egl", "osmesa"),
                                 "osmesa"),
    "PYOPENGL_PLATFORM egl, egl missing": ({"PYOPENGL_PLATFORM": "egl"}, "linux", ("osmesa",),
                                           None),
    "PYOPENGL_PLATFORM glx": ({"PYOPENGL_PLATFORM": "glx"}, "linux", ("egl", "osmesa"), None),
}


@pytest.mark.parametrize("case", sorted(CHOICES))
def test_backend_choice(case: str) -> None:
    environ, platform, available, expected = CHOICES[case]
    assert choose_backend(environ, platform, _loads(*available)) == expected


def _python(code: str, **env: str | None) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter with DISPLAY/WAYLAND_DISPLAY/MUJOCO_GL removed,
    then ``env`` applied (None removes)."""
    environ = {k: v for k, v in os.environ.items()
               if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL", "PYOPENGL_PLATFORM")}
    environ["PYTHONPATH"] = os.pathsep.join([str(ROOT / "tests"), str(ROOT)])
    environ.update({k: v for k, v in env.items() if v is not None})
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=environ, cwd=ROOT, timeout=300)


GL_OF_MUJOCO = ("import os, sys, mujoco; "
                "print(os.environ.get('MUJOCO_GL'), "
                "sys.modules['mujoco.rendering.classic.gl_context'].GLContext.__module__)")


@pytest.mark.parametrize("package", [
    "impact_eval.bench",  # imports mujoco at its top, before any impact_envs import
    pytest.param("impact_learn", marks=pytest.mark.slow),
    pytest.param("impact_lerobot", marks=pytest.mark.slow),
    pytest.param("impact_robosuite", marks=pytest.mark.slow),
])
def test_a_package_picks_egl_before_mujoco_loads(package: str) -> None:
    """Each package __init__ chooses before its modules' third-party imports run."""
    if package == "impact_robosuite":
        pytest.importorskip("robosuite")
    done = _python(f"import {package}; {GL_OF_MUJOCO}")
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["egl", "mujoco.egl"]


@pytest.fixture
def fresh_gl(monkeypatch: pytest.MonkeyPatch):
    """``_gl`` as before any choice, mujoco not imported yet, no display, MUJOCO_GL unset
    (all restored afterwards)."""
    from impact_envs import _gl

    monkeypatch.setattr(_gl, "chosen", None)
    monkeypatch.delitem(sys.modules, "mujoco")
    for name in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setattr(_gl, "library_loads", _loads("egl", "osmesa"))
    return _gl


@pytest.mark.parametrize("env,expected", [
    ({}, "egl"),
    ({"MUJOCO_GL": "osmesa"}, "osmesa"),
    ({"MUJOCO_GL": "glfw"}, "glfw"),
    ({"DISPLAY": ":99"}, None),
    ({"WAYLAND_DISPLAY": "wayland-1"}, None),
])
def test_select_sets_mujoco_gl_only_when_unset_and_headless(
        fresh_gl, monkeypatch: pytest.MonkeyPatch, env: dict, expected: str | None) -> None:
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    fresh_gl.select_headless_backend()
    assert os.environ.get("MUJOCO_GL") == expected


def test_select_does_nothing_once_mujoco_is_imported(fresh_gl, monkeypatch) -> None:
    """Too late to choose: MuJoCo read MUJOCO_GL on import (check_rendering reports it)."""
    monkeypatch.setitem(sys.modules, "mujoco", object())
    assert fresh_gl.select_headless_backend() is None
    assert "MUJOCO_GL" not in os.environ


def test_camera_observation_renders_without_mujoco_gl_or_display() -> None:
    """The README's camera observation on a machine without a display, nothing set."""
    done = _python(
        "import gymnasium as gym, impact_envs\n"
        "from impact_envs import ObservationOptions\n"
        "env = gym.make('IMPACT/Hammer-v1', observation=ObservationOptions(obs_mode='rgb', "
        "cameras=('overview',), image_width=32, image_height=24))\n"
        "obs, _ = env.reset(seed=0)\n"
        "img = obs['overview_rgb']\n"
        "print(img.shape, img.dtype, int(img.max()) > 0, int(img.std() > 1))\n"
        "import os, sys\n"
        "print(os.environ['MUJOCO_GL'], "
        "sys.modules['mujoco.rendering.classic.gl_context'].GLContext.__module__)\n")
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["(24,", "32,", "3)", "uint8", "True", "1", "egl",
                                   "mujoco.egl"]


def test_a_failing_renderer_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    """Whatever the GL layer raises (FatalError, PyOpenGL's AttributeError, ImportError),
    ``make_renderer`` turns it into one RenderingError line naming what to set."""
    import mujoco

    from impact_control.errors import ImpactError, RenderingError
    from impact_envs import _gl

    for exc in (mujoco.FatalError("an OpenGL platform library has not been loaded\ninto "
                                  "this process"),
                AttributeError("'NoneType' object has no attribute 'glGetError'"),
                ImportError("libEGL.so.1: cannot open")):
        def fail(*args, exc=exc, **kwargs):
            raise exc
        monkeypatch.setattr(mujoco, "Renderer", fail)
        with pytest.raises(RenderingError) as info:
            _gl.make_renderer(None, 8, 8)
        message = str(info.value)
        assert "\n" not in message and "set MUJOCO_GL=egl" in message
        assert type(exc).__name__ in message and isinstance(info.value, ImpactError)


@pytest.mark.slow
def test_no_gl_context_is_one_line_at_construction() -> None:
    """glfw without a display cannot make a context: RenderingError names MUJOCO_GL=egl."""
    done = _python(
        "import gymnasium as gym, impact_envs\n"
        "from impact_control.errors import RenderingError\n"
        "try:\n"
        "    gym.make('IMPACT/Dumbbell-v1', observation='rgbd')\n"
        "except RenderingError as exc:\n"
        "    print(str(exc))\n", MUJOCO_GL="glfw")
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.strip().splitlines()
    assert len(lines) == 1 and "MUJOCO_GL=glfw, no display" in lines[0]
    assert "set MUJOCO_GL=egl" in lines[0]


def test_mujoco_imported_first_is_named_in_the_error(monkeypatch: pytest.MonkeyPatch) -> None:
    """A script that imported mujoco before impact_envs (nothing picked, no display, nothing
    set) is told why, and what to set."""
    import mujoco

    from impact_control.errors import RenderingError
    from impact_envs import _gl

    monkeypatch.setattr(_gl, "chosen", None)
    for name in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(mujoco, "Renderer", lambda *a, **k: (_ for _ in ()).throw(
        mujoco.FatalError("an OpenGL platform library has not been loaded")))
    with pytest.raises(RenderingError, match=r"MUJOCO_GL=unset, no display \(mujoco was "
                                             r"imported before impact_envs"):
        _gl.make_renderer(None, 8, 8)


def test_a_size_error_is_not_reported_as_gl(monkeypatch: pytest.MonkeyPatch) -> None:
    """mujoco.Renderer's ValueError (a size beyond the offscreen buffer) is the caller's
    argument and passes through unchanged."""
    import mujoco

    from impact_envs import _gl

    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    with pytest.raises(ValueError, match="width"):
        _gl.make_renderer(model, 8, 100000)
