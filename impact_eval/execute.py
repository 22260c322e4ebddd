"""Run a validated ``Plan``: create the output directory, log episodes, write the report."""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from impact_envs.versions import version_of
from impact_eval import runinfo
from impact_eval.csvio import EpisodeLog
from impact_eval.prepare import Plan
from impact_eval.report import EPISODES_CSV, write_report
from impact_eval.sweep import plan_tasks, run_sweep


@dataclass(frozen=True)
class Result:
    """What a sweep produced."""

    episodes_run: int
    rows: int
    summary: Path
    plots: list[Path]


def _run_record(plan: Plan, command: list[str]) -> dict:
    """Initial ``run.json`` content; earlier invocations of a resumed run are kept. The spec is
    in it once, inside ``"identity"`` (``RunIdentity.to_json``, as identity.json)."""
    cfg = plan.config
    previous = plan.previous_run or {}
    return {
        "command": command,
        "identity": plan.identity.to_json(),
        "env": {
            "id": plan.env.env_id,
            "version": version_of(plan.env.env_id),
            "param_name": plan.env.param_name,
            "control_dt_s": plan.env.control_dt,
            "policy_dt_s": plan.env.policy_dt,
            "max_episode_steps": plan.env.max_episode_steps,
            "spec": json.loads(plan.env.spec_json),
        },
        "run_options": {k: str(v) if isinstance(v, Path) else v
                        for k, v in asdict(cfg.options).items()},
        "versions": runinfo.package_versions(),
        "git": previous.get("git") or runinfo.git_state(),  # the code that wrote the first rows
        "host": runinfo.host_info(),
        "invocations": previous.get("invocations", []),
    }


def execute(plan: Plan, command: list[str]) -> Result:
    """Run the plan; ``run.json`` records each invocation's wall time and outcome
    (``command``: the invocation as given, an ``impact-eval`` argv or an ``evaluate`` call)."""
    plan.out.mkdir(parents=True, exist_ok=True)
    record = _run_record(plan, command)
    invocation = {
        "started_utc": runinfo.utc_now(),
        "resume": bool(plan.done),
        "episodes_already_done": len(plan.done),
        "git": runinfo.git_state(),
        "status": "running",
    }
    if plan.config.options.allow_code_change:
        invocation["allow_code_change"] = True
    record["invocations"].append(invocation)
    runinfo.write_identity(plan.out, plan.identity)
    runinfo.write_run_json(plan.out, record)
    t0 = time.perf_counter()
    log = EpisodeLog(plan.out / EPISODES_CSV)
    log.open()
    try:
        run = run_sweep(plan.config, plan_tasks(plan.config, plan.done), log.append)
    except BaseException:
        invocation.update(status="failed", wall_s=round(time.perf_counter() - t0, 3))
        runinfo.write_run_json(plan.out, record)
        raise
    finally:
        log.close()
    rows = log.finalize()
    sweep_wall = time.perf_counter() - t0
    summary, plots = write_report(plan.out)
    invocation.update(
        status="complete",
        episodes_run=run,
        sweep_wall_s=round(sweep_wall, 3),
        wall_s=round(time.perf_counter() - t0, 3),
        episodes_per_s=round(run / sweep_wall, 3) if sweep_wall > 0 else None,
    )
    runinfo.write_run_json(plan.out, record)
    return Result(episodes_run=run, rows=rows, summary=summary, plots=plots)
