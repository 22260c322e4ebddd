"""``python -m impact_experiments.demo_sink``: does a mass-blind demonstrator carry a
heavier hammer over the basket wall? (issue 55 item 1, no training)

Runs, on ``IMPACT/HammerBasket-v1`` under their baselines' controller (plain impedance with
the ``authors_sim`` preset: their impedance, limits and target filter, no feedforward; their
observer runs but nothing reads it), two demonstrators whose height offset is the one of a
``--offset-kg`` hammer whatever the hammer weighs (what a Vanilla policy trained at one mass
learns):

- ``rebased``: the authors' demonstrator (``impact_envs.policies.authors_demonstrator``):
  targets re-based on the measured TCP, at most 4 cm toward the waypoint per step, plus the
  offset;
- ``absolute``: our expert (``scripted_hammer_basket``, ``compensation="privileged"`` given
  the ``--offset-kg`` mass): absolute targets ramped at 0.25 m/s, plus the same offset.

Per episode it writes, over the steps on which the hand is closed, the hammer is lifted
(origin 5 cm above the table) and its origin crosses the basket wall's band (within 10 cm
outside to 5 cm inside the wall line, in x or y), the hammer's lowest point above the wall's
top (``clearance_m``, from the geoms' bounding boxes; NaN if it never crossed closed) and the
TCP's lowest height above the table (``crossing_tcp_m``); whether the hammer touched the
basket while carried (hand closed, hammer lifted: ``hit``); and the success at the end (900
steps, 30 s). Rows go to ``--out`` (CSV, a new file: an existing one is refused, nothing is
overwritten), one per episode, cell by cell as they finish; episode seeds are
``seed + 1000 k + e`` for mass index ``k``, so use seeds you do not report.

    python -m impact_experiments.demo_sink --masses 0.75,1.25,1.75 --episodes 20 \\
        --seed 0 --out results/hammer_basket_diag/demo_sink.csv
"""

from __future__ import annotations

import csv
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError
from impact_eval.envs import check_masses

ENV_ID = "IMPACT/HammerBasket-v1"
DEMOS = ("rebased", "absolute", "rebased_speed", "rebased_their_grasp")
"""``rebased``: their demonstrator at their 0.04 m lead per step with our grasp;
``rebased_speed``: its step scaled to their 50 Hz speed; ``rebased_their_grasp``: their grasp
(``authors_demonstrator.RATE_MAPPINGS``, ``GRASPS``)."""
PRIVILEGED = "privileged"
"""``--offset-kg privileged``: each episode's offset is its own mass (their demos)."""
COLUMNS = ("demo", "offset_kg", "mass_kg", "seed", "episode", "success", "hit", "clearance_m",
           "crossing_tcp_m", "first_success_step")


def _aabb_z(model, data, geoms: np.ndarray) -> tuple[float, float]:
    """(lowest, highest) world z of the geoms' bounding boxes [m]."""
    low, high = math.inf, -math.inf
    for g in geoms:
        rot = data.geom_xmat[g].reshape(3, 3)
        centre = data.geom_xpos[g] + rot @ model.geom_aabb[g, :3]
        reach = float(np.abs(rot[2]) @ model.geom_aabb[g, 3:])
        low, high = min(low, centre[2] - reach), max(high, centre[2] + reach)
    return low, high


def _touching(data, first: np.ndarray, second: np.ndarray) -> bool:
    """Whether a geom of ``first`` touches a geom of ``second``."""
    pairs = data.contact.geom[: data.ncon]
    a, b = np.isin(pairs[:, 0], first), np.isin(pairs[:, 1], second)
    c, e = np.isin(pairs[:, 1], first), np.isin(pairs[:, 0], second)
    return bool(np.any((a & b) | (c & e)))


def _policy(demo: str):
    """The demonstrator; its offset mass is given to ``reset``."""
    from impact_envs.policies.authors_demonstrator import RebasedDemonstrator, rebased_spec
    from impact_envs.policies.scripted_hammer_basket import hammer_basket_expert

    if demo == "absolute":
        return hammer_basket_expert("privileged")
    return RebasedDemonstrator(spec=rebased_spec("speed" if demo == "rebased_speed" else "lead"),
                               grasp="theirs" if demo == "rebased_their_grasp" else "ours")


class CarryProbe:
    """Per step of one episode, what the hammer does while the hand is closed and the hammer
    lifted (module docstring): its clearance over the wall while crossing it, the TCP's
    lowest height there, a touch of the basket, the first success step, and the hammer
    origin's highest point above the table while closed (``max_lift_m``)."""

    def __init__(self, env) -> None:
        from impact_envs.tasks.hammer_basket import TABLE_TOP_M

        self.m, self.d = env.unwrapped.sim.model, env.unwrapped.sim.data
        self.body = self.m.body("hammer").id
        self.hammer = np.flatnonzero(self.m.geom_bodyid == self.body)
        self.basket = np.flatnonzero(self.m.geom_bodyid == self.m.body("basket").id)
        self.table = TABLE_TOP_M
        self.clearance, self.tcp_min, self.max_lift = math.inf, math.inf, -math.inf
        self.hit, self.first, self.step, self.info = False, -1, 0, {}

    def update(self, obs: dict, action: np.ndarray, info: dict) -> None:
        from impact_envs.tasks.hammer_basket import SUCCESS_HALF_M

        m, d = self.m, self.d
        if self.first < 0 and info.get("is_success", False):
            self.first = self.step
        self.step, self.info = self.step + 1, info
        closed = action[-1] > 0.0
        height = float(obs["object_pos"][2]) - self.table
        if closed:
            self.max_lift = max(self.max_lift, height)
        if not (closed and height > 0.05):
            return
        rel = np.abs(d.xpos[self.body, :2] - obs["goal_pos"][:2])
        if np.all(rel <= SUCCESS_HALF_M + 0.1) and np.any(rel >= SUCCESS_HALF_M - 0.05):
            self.tcp_min = min(self.tcp_min, float(obs["ee_pos"][2]) - self.table)
            wall_top = _aabb_z(m, d, self.basket)[1]
            self.clearance = min(self.clearance, _aabb_z(m, d, self.hammer)[0] - wall_top)
        self.hit = self.hit or _touching(d, self.hammer, self.basket)

    def row(self) -> dict[str, object]:
        """The episode's columns (NaN where nothing was measured)."""
        def finite(x: float) -> float:
            return x if math.isfinite(x) else math.nan

        return {"success": int(bool(self.info.get("is_success", False))), "hit": int(self.hit),
                "clearance_m": finite(self.clearance), "crossing_tcp_m": finite(self.tcp_min),
                "first_success_step": self.first}


def run_cell(args: tuple[str, float | str, float, int, int, int]) -> list[dict[str, object]]:
    """The rows of one (demo, offset, mass) cell's episodes."""
    import gymnasium as gym

    import impact_envs  # noqa: F401 - registers the envs
    from impact_control.policy import stack_obs

    demo, offset_kg, mass, seed, k, episodes = args
    env = gym.make(ENV_ID, controller="impedance", controller_preset="authors_sim")
    policy, rows = _policy(demo), []
    offset_mass = mass if offset_kg == PRIVILEGED else float(offset_kg)
    for e in range(episodes):
        obs, _ = env.reset(seed=seed + 1000 * k + e, options={"object_mass": mass})
        policy.reset(1, np.array([offset_mass]))
        probe = CarryProbe(env)
        for _ in range(900):
            action = np.asarray(policy.act(stack_obs([obs]))[0])
            obs, _, _, _, info = env.step(action)
            probe.update(obs, action, info)
        rows.append({"demo": demo, "offset_kg": offset_kg, "mass_kg": mass,
                     "seed": seed + 1000 * k + e, "episode": e, **probe.row()})
    env.close()
    return rows


def _offset(text: str) -> float | str | None:
    """``--offset-kg``'s value, or None if invalid."""
    if text == PRIVILEGED:
        return text
    try:
        value = float(text)
    except ValueError:
        return None
    return value if 0.0 < value < math.inf else None


def main(argv: list[str] | None = None) -> None:
    """Entry point; bad input exits 2 with one line, before anything is written."""
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--masses", default="0.75,1.25,1.75", help="comma list [kg]")
    p.add_argument("--offset-kg", default="0.6",
                   help="the offset's mass [kg], or 'privileged': each episode's own mass")
    p.add_argument("--demos", default=",".join(DEMOS))
    p.add_argument("--episodes", type=int, default=20)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args(argv)
    demos = [x for x in args.demos.split(",") if x]
    if not demos or any(x not in DEMOS for x in demos):
        p.fail(f"invalid --demos {args.demos!r}; valid: a comma list of {', '.join(DEMOS)}")
    try:
        masses = [float(x) for x in args.masses.split(",") if x]
    except ValueError:
        p.fail(f"invalid --masses {args.masses!r}; valid: a comma list of masses in kg")
    if args.episodes < 1 or args.workers < 1 or not masses:
        p.fail("--episodes and --workers must be >= 1 and --masses name at least one mass")
    offset = _offset(args.offset_kg)
    if offset is None:
        p.fail(f"invalid --offset-kg {args.offset_kg!r}; valid: a mass > 0 [kg] or {PRIVILEGED}")
    if args.out.exists():
        p.fail(f"--out {str(args.out)!r} exists; valid: a new file (nothing is overwritten)")
    try:
        check_masses(ENV_ID, masses)
    except ImpactError as exc:
        p.fail(" ".join(str(exc).split()))
    cells = [(demo, offset, mass, args.seed, k, args.episodes)
             for demo in demos for k, mass in enumerate(masses)]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("x", newline="") as f, ProcessPoolExecutor(args.workers) as pool:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        for rows in pool.map(run_cell, cells):
            writer.writerows(rows)
            f.flush()
            r = rows[0]
            ok = [x for x in rows if not math.isnan(x["clearance_m"])]
            median = np.median([x["clearance_m"] for x in ok]) if ok else math.nan
            print(f"{r['demo']} {r['mass_kg']} kg: success {sum(x['success'] for x in rows)}/"
                  f"{len(rows)}, hit the basket {sum(x['hit'] for x in rows)}, clearance over "
                  f"the wall median {median:.3f} m", flush=True)

if __name__ == "__main__":
    main()
