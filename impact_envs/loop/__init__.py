"""The closed loop above ``robot/`` and ``control/``: sense -> control -> actuate -> step."""

from impact_envs.loop.closed_loop import ClosedLoop, StepTrace, TickTargets, control_tick

__all__ = ["ClosedLoop", "StepTrace", "TickTargets", "control_tick"]
