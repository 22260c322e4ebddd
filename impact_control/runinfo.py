"""Provenance of a run, from the standard library only: time, host and package versions.

Shared by the benchmark's ``run.json`` (``impact_eval.runinfo``) and the robot runner's
(``impact_franka.session``), so the runner records the same fields without the benchmark.
"""

from __future__ import annotations

import os
import platform
import sys
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

CONTROL_PACKAGES = ("impact-robotics", "numpy", "numba", "pin", "pandas", "pylibfranka")
"""Distributions a robot run records (``package_versions``' default)."""


def package_versions(names: tuple[str, ...] = CONTROL_PACKAGES) -> dict[str, str | None]:
    """Installed version of each of ``names`` (``None`` if not installed); this package's own
    is marked "(source tree)" when it runs uninstalled."""
    versions: dict[str, str | None] = {}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    if "impact-robotics" in versions and versions["impact-robotics"] is None:
        from impact_control import __version__

        versions["impact-robotics"] = f"{__version__} (source tree)"
    return versions


def utc_now() -> str:
    """Current UTC time, ISO 8601 to the second."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def host_info() -> dict[str, object]:
    """Python, platform, CPU model, widest SIMD and CPU count (context for wall times, and for
    bytes that differ on another CPU: the compiled kernels and libraries pick their code paths
    by instruction set, docs/results.md "Reproducibility")."""
    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        **cpu_info(),
        "cpu_count": os.cpu_count(),
    }


def cpu_info() -> dict[str, str]:
    """``cpu_model`` and ``simd`` (avx512 / avx2 / sse4_2 / other) from /proc/cpuinfo."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return {"cpu_model": platform.processor() or "unknown", "simd": "unknown"}
    fields = {k.strip(): v.strip() for k, v in (line.split(":", 1) for line in
                                                  text.splitlines()[:40] if ":" in line)}
    flags = set(fields.get("flags", "").split())
    simd = next((name for name, flag in (("avx512", "avx512f"), ("avx2", "avx2"),
                                         ("sse4_2", "sse4_2")) if flag in flags), "other")
    return {"cpu_model": fields.get("model name", "unknown"), "simd": simd}
