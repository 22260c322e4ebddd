"""How far above the TCP a demonstration commands the carried load: the offset a policy with
delta actions (target = measured pose + action) would have to learn.

Run ``python -m impact_experiments.demo_offsets --data data/hb_vanilla400.zarr`` on an
``impact-collect`` store. For every demo, over the steps where the object is at least
``--lifted-m`` above its start, the commanded TCP height minus the measured one
(``action[:, 2] - ee_pos[:, 2]``): its median per demo, then the mean of those medians per mass
band, beside ``m g / K`` (the sag of a mass m under the impedance stiffness K, 400 N/m).
Prints one line per band and writes nothing.
"""

from __future__ import annotations

import argparse

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_learn.store_check import open_store

GRAVITY_M_S2 = 9.81


def offsets(data: str, lifted_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(mass [kg], median commanded-minus-measured TCP z while lifted [m]) per demo that
    lifted its object."""
    root = open_store(data)
    missing = [k for k in ("data/action", "data/ee_pos", "data/object_pos",
                           "meta/episode_param") if k not in root]
    if missing:
        raise InvalidArgumentError(f"{data} lacks {', '.join(missing)}; valid: a store written "
                                   "by impact-collect with a mass parameter")
    action, ee = root["data/action"][:], root["data/ee_pos"][:]
    obj = root["data/object_pos"][:]
    ends, masses = root["meta/episode_ends"][:], root["meta/episode_param"][:]
    kept_m, kept_dz = [], []
    for start, end, mass in zip(np.r_[0, ends[:-1]], ends, masses, strict=True):
        lifted = obj[start:end, 2] > obj[start, 2] + lifted_m
        if lifted.sum() >= 10:
            kept_m.append(float(mass))
            kept_dz.append(float(np.median((action[start:end, 2] - ee[start:end, 2])[lifted])))
    return np.array(kept_m), np.array(kept_dz)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="an impact-collect store (.zarr)")
    parser.add_argument("--bands", type=int, default=4, help="mass bands (equal widths)")
    parser.add_argument("--lifted-m", type=float, default=0.05,
                        help="the object counts as carried this far above its start [m]")
    parser.add_argument("--stiffness", type=float, default=400.0, help="K [N/m]")
    args = parser.parse_args(argv)
    if args.bands < 1 or args.lifted_m <= 0 or args.stiffness <= 0:
        parser.error("--bands must be >= 1, --lifted-m and --stiffness > 0")
    try:
        mass, dz = offsets(args.data, args.lifted_m)
    except InvalidArgumentError as exc:
        parser.error(str(exc))
    if not len(mass):
        parser.error(f"--data {args.data}: no demo lifted its object by {args.lifted_m} m")
    edges = np.linspace(mass.min(), mass.max(), args.bands + 1)
    print(f"{len(mass)} demos that lifted their object; commanded minus measured TCP z while "
          "carried (median per demo, mean over the band):")
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        band = (mass >= lo) & (mass <= hi if hi == edges[-1] else mass < hi)
        mid = 0.5 * (lo + hi)
        sag_cm = 100 * mid * GRAVITY_M_S2 / args.stiffness
        print(f"  {lo:.2f}-{hi:.2f} kg: {band.sum():3d} demos, offset "
              f"{100 * dz[band].mean():.2f} cm (m g / K at {mid:.2f} kg: {sag_cm:.2f} cm)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
