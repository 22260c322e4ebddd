"""The kernel-cache guard: stale numba caches are deleted when any kernel source changes."""

from __future__ import annotations

import re
from pathlib import Path

import impact_envs
from impact_control import jit_cache

ENVS_DIR = Path(impact_envs.__file__).resolve().parent
SIM_FOLDERS = (ENVS_DIR / "loop", ENVS_DIR / "robot")


def _names(paths: list[Path]) -> set[str]:
    root = jit_cache.PACKAGE_DIR.parent
    return {p.relative_to(root).as_posix() for p in paths}


def test_kernel_sources_are_every_module_with_njit():
    for folders in ((jit_cache.PACKAGE_DIR,), SIM_FOLDERS):
        with_njit = [p for folder in folders for p in folder.rglob("*.py")
                     if re.search(r"^@njit", p.read_text(), re.MULTILINE)]
        assert _names(jit_cache.kernel_sources(folders)) == _names(with_njit)
    assert {"impact_control/kernels.py", "impact_control/limits.py"} <= _names(
        jit_cache.kernel_sources())
    assert "impact_envs/loop/tick.py" in _names(jit_cache.kernel_sources(SIM_FOLDERS))


def _fake_cache(tmp_path: Path) -> tuple[list[Path], Path]:
    pkg = tmp_path / "pkg"
    (pkg / "__pycache__").mkdir(parents=True)
    sources = [pkg / "kern.py", pkg / "loop.py"]
    for src in sources:
        src.write_text(f"# {src.stem}\n")
    for name in ("kern.tick-10.py311.nbi", "kern.tick-10.py311.1.nbc", "loop.fused-4.py311.nbi",
                 "other.f-1.py311.nbi"):
        (pkg / "__pycache__" / name).write_bytes(b"x")
    return sources, pkg / "__pycache__"


def test_refresh_deletes_kernels_of_a_changed_source_set_once(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    sources, cache = _fake_cache(tmp_path)
    digest = jit_cache.sources_digest(sources)
    assert jit_cache.refresh_cache(sources, digest) == 3  # no stamp yet: everything of ours
    assert sorted(p.name for p in cache.iterdir()) == [jit_cache.STAMP_NAME,
                                                       "other.f-1.py311.nbi"]
    (cache / "loop.fused-4.py311.nbi").write_bytes(b"x")  # numba recompiled
    assert jit_cache.refresh_cache(sources, digest) == 0  # unchanged sources: kept
    sources[0].write_text("# kern, edited\n")  # only the callee changed
    new_digest = jit_cache.sources_digest(sources)
    assert new_digest != digest
    assert jit_cache.refresh_cache(sources, new_digest) == 1  # the caller's cache goes too
    assert (cache / jit_cache.STAMP_NAME).read_text().strip() == new_digest


def test_refresh_covers_numba_cache_dir(tmp_path, monkeypatch):
    sources, _ = _fake_cache(tmp_path)
    user = tmp_path / "numba_cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(user))
    mirror = jit_cache.cache_dirs(sources[0])[1]
    assert mirror.is_relative_to(user)
    mirror.mkdir(parents=True)
    (mirror / "kern.tick-10.py311.nbi").write_bytes(b"x")
    jit_cache.refresh_cache(sources, "new")
    assert not (mirror / "kern.tick-10.py311.nbi").exists()
    assert (mirror / jit_cache.STAMP_NAME).read_text().strip() == "new"


def test_digest_covers_the_modules_of_the_named_tuples_kernels_take():
    """Moving or renaming a kernel-argument named tuple made cached kernels unloadable (they
    pickle the type by module path); its module must count in the digest, @njit or not."""
    from impact_control.arm_model import DynamicsArrays
    from impact_envs.robot.sim import SimArrays

    sim_covered = _names(jit_cache.digest_sources((*SIM_FOLDERS, jit_cache.PACKAGE_DIR)))
    modules = {t.__module__.replace(".", "/") + ".py" for t in (DynamicsArrays, SimArrays)}
    assert modules <= sim_covered  # the loop's kernels take both
    covered = _names(jit_cache.digest_sources())
    assert "impact_control/arm_model.py" in covered
    assert "impact_control/impedance_config.py" in covered  # no @njit line, types kernels read
    presets = (jit_cache.PACKAGE_DIR / "presets.py").read_bytes()
    assert not jit_cache.NJIT_MARK.search(presets)
    assert "impact_control/presets.py" in covered


def test_editing_a_module_without_njit_changes_the_digest(tmp_path):
    """A changed type module (no @njit line) must change the stamp, so the kernels recompile."""
    kern = tmp_path / "kern.py"
    kern.write_text("@njit\ndef f():\n    pass\n")
    types = tmp_path / "types.py"
    types.write_text("class A(NamedTuple):\n    x: float\n")
    before = jit_cache.sources_digest([kern, types])
    types.write_text("class B(NamedTuple):\n    x: float\n")
    assert jit_cache.sources_digest([kern, types]) != before
