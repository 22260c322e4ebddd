"""``--resume`` against the code and the checkpoints that wrote a run's rows.

A resumed run appends rows to those an earlier invocation wrote; they belong in one table
only if the same code and the same policy weights wrote them. ``check_same_code`` compares
this checkout's git state with the one that wrote the run's last rows (each invocation
records its own in run.json); ``--allow-code-change`` lets a resume through on purpose
(``reproduce`` reruns committed cells that way and compares the bytes itself), and the
invocation records that it did. The checkpoints' fingerprints are part of the run's
identity (``RunIdentity.policy_fingerprints``) and are compared strictly.
"""

from __future__ import annotations

from impact_control.errors import InvalidArgumentError

FLAG = "--allow-code-change"


def recorded_git(run: dict | None) -> dict | None:
    """The git state that wrote ``run``'s last rows: its last invocation's, else the
    run's own (runs from before invocations recorded it); None when nothing is recorded."""
    if not isinstance(run, dict):
        return None
    for invocation in reversed(run.get("invocations") or []):
        if isinstance(invocation, dict) and isinstance(invocation.get("git"), dict):
            return invocation["git"]
    git = run.get("git")
    return git if isinstance(git, dict) else None


def code_difference(was: dict | None, now: dict) -> str | None:
    """Why the code that wrote a run (``was``, a ``runinfo.git_state``) may differ from
    ``now``'s; None when it is the same, or when either side was not in git."""
    if was is None or was.get("sha") is None or now.get("sha") is None:
        return None
    if was["sha"] != now["sha"]:
        return (f"its rows were written at commit {str(was['sha'])[:12]}, this checkout is at "
                f"{str(now['sha'])[:12]}")
    if "code_diff" not in was:  # recorded before code_diff: only "dirty" tells
        return "its rows were written from a modified checkout" if was.get("dirty") else None
    if was["code_diff"] != now.get("code_diff"):
        return "its rows were written with other uncommitted changes than this checkout's"
    return None


def check_same_code(run: dict | None, now: dict, allow: bool) -> None:
    """Refuse to resume ``run`` from other code than wrote its last rows, unless ``allow``."""
    reason = code_difference(recorded_git(run), now)
    if reason is not None and not allow:
        raise InvalidArgumentError(
            f"cannot resume: {reason}; rows from two versions of the code would share one "
            f"table. Use another --out, or pass {FLAG} to resume anyway (recorded in run.json)")


def check_fingerprints(was: object, now: dict[str, str | None]) -> None:
    """Each method present in both must load the same checkpoint bytes (runs recorded
    before fingerprints are not checked)."""
    if not isinstance(was, dict):
        return
    for method, digest in now.items():
        before = was.get(method)
        if method in was and before != digest:
            raise InvalidArgumentError(
                f"cannot resume: method {method!r} ran with checkpoint fingerprint "
                f"{str(before)[:12]} and would now load {str(digest)[:12]} (another "
                "checkpoint); use the same checkpoint or another --out")
