"""``python -m impact_experiments.contact_params``: the contact parameters the compiled
HammerBasket model uses between the fingers and the hammer (issue 55 item 6), to set beside
the authors' MJCF (``../shared/reference/authors_impact.md``, scene facts).

Prints ``noslip_iterations``, the cone and ``impratio``, each finger-pad and hammer geom's
``solref`` / ``solimp`` / friction / condim, and every explicit contact pair (an explicit
``<pair>`` takes its own ``solref`` / ``solimp``, not the geoms'; MuJoCo's defaults where the
pair sets none).

    python -m impact_experiments.contact_params [--env IMPACT/HammerBasket-v1]
"""

from __future__ import annotations

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError


def lines(env_id: str) -> list[str]:
    """The printed report of ``env_id``'s compiled model."""
    import gymnasium as gym

    import impact_envs  # noqa: F401 - registers the envs
    from impact_eval.envs import check_env_id

    env = gym.make(check_env_id(env_id))
    m = env.unwrapped.sim.model
    if "hammer" not in (m.body(i).name for i in range(m.nbody)):
        env.close()
        raise InvalidArgumentError(f"--env {env_id!r} has no body named hammer; valid: "
                                   "IMPACT/HammerBasket-v1 or IMPACT/Hammer-v1")
    out = [f"noslip_iterations {m.opt.noslip_iterations}, cone {m.opt.cone} (1: elliptic), "
           f"impratio {m.opt.impratio:g}, timestep {m.opt.timestep:g} s"]
    hammer = m.body("hammer").id
    for g in range(m.ngeom):
        body = m.body(m.geom_bodyid[g]).name
        if m.geom_bodyid[g] == hammer or "pad" in m.geom(g).name:
            out.append(f"geom {body}/{m.geom(g).name}: solref {m.geom_solref[g].round(4).tolist()}"
                       f", solimp {m.geom_solimp[g][:3].round(4).tolist()}, friction "
                       f"{m.geom_friction[g].round(3).tolist()}, condim {m.geom_condim[g]}")
    for p in range(m.npair):
        out.append(f"pair {m.geom(m.pair_geom1[p]).name}-{m.geom(m.pair_geom2[p]).name}: solref "
                   f"{m.pair_solref[p].round(4).tolist()}, solimp "
                   f"{m.pair_solimp[p][:3].round(4).tolist()}, friction "
                   f"{m.pair_friction[p].round(3).tolist()}, condim {m.pair_dim[p]}")
    env.close()
    return out


def main(argv: list[str] | None = None) -> None:
    """Entry point."""
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--env", default="IMPACT/HammerBasket-v1")
    args = p.parse_args(argv)
    try:
        report = lines(args.env)
    except ImpactError as exc:
        p.fail(" ".join(str(exc).split()))
    print("\n".join(report))


if __name__ == "__main__":
    main()
