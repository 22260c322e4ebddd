"""Configuration of the internal model stage (network, learning, surprise gate, replay)."""

from __future__ import annotations

from dataclasses import dataclass

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.validation import check_positive

LEARNERS: tuple[str, ...] = ("numpy", "numba")
"""Valid ``InternalModelConfig.learner`` values."""


@dataclass(frozen=True)
class InternalModelConfig:
    """Internal model network, online learner, surprise gate and replay buffer.

    Attributes:
        history_length: Ticks L of per-tick features fed to the network (paper: 32).
        hidden_sizes: Widths of the tanh hidden layers (own choice: (64, 64)).
        learning_rate: Plain SGD step size on the normalized MSE (default 0.1; paper: 0.01).
        surprise_open_n: Gate opens when the force surprise reaches this value [N] (default
            2.5, 4.5x the largest excursion of the simulated estimator's force noise at
            rest, docs/presets.md "Presets"; paper: 5).
        surprise_release_n: Open gate closes when the force surprise falls below this [N]
            (own choice 0.5; equal to ``surprise_open_n`` gives the literal single threshold).
        slow_rate_max: Learning only while the slow-wrench rate (|dw_slow/dt|_force divided by
            eta_f * clip_f, dimensionless) is at most this (default 1.5: pauses only while
            w_slow slews on several force axes at once; paper: 0.2).
        update_every: Ticks between SGD steps while learning (own choice: 5).
        batch_size: Samples per SGD step: the current one plus replayed ones (own choice: 16).
        replay_capacity: FIFO capacity of the replay buffer [samples] (own choice: 256).
        replay_period: Ticks between stored quasi-steady samples (own choice: 10, i.e. 10 ms).
        seed: Seed of the weight initialisation and of replay sampling.
        learner: Where replay and SGD run: ``"numba"`` (default: inside the tick, spread
            over ticks: a bounded tick, ``internal_model/learner.py``) or ``"numpy"`` (in
            Python after the tick, NumPy BLAS, one whole step on its tick: the learner of the
            tables before 2026-11-26).
        samples_per_tick: With ``learner="numba"``, batch samples processed per tick (own
            choice 4: a batch-16 step over 4 ticks; docs/controller.md "A bounded tick").
        wrench_feature: Feed the estimated wrench to the network (default True, as both
            presets). False zeroes those six inputs, so the model predicts from the robot's
            state (joints, gripper, TCP position) alone; an experiment, docs/results.md §1.
    """

    history_length: int = 32
    hidden_sizes: tuple[int, ...] = (64, 64)
    learning_rate: float = 0.1
    surprise_open_n: float = 2.5
    surprise_release_n: float = 0.5
    slow_rate_max: float = 1.5
    update_every: int = 5
    batch_size: int = 16
    replay_capacity: int = 256
    replay_period: int = 10
    seed: int = 0
    learner: str = "numba"
    samples_per_tick: int = 4
    wrench_feature: bool = True

    def __post_init__(self) -> None:
        object.__setattr__(self, "hidden_sizes", tuple(int(h) for h in self.hidden_sizes))
        for name in ("history_length", "update_every", "batch_size", "replay_capacity"):
            if int(getattr(self, name)) < 1:
                raise InvalidArgumentError(f"invalid {name} {getattr(self, name)!r}; valid: >= 1")
        if self.replay_period < 1:
            raise InvalidArgumentError(f"invalid replay_period {self.replay_period!r}; valid: >= 1")
        if not self.hidden_sizes or min(self.hidden_sizes) < 1:
            raise InvalidArgumentError(
                f"invalid hidden_sizes {self.hidden_sizes!r}; valid: non-empty, all >= 1"
            )
        check_choice("internal_model.learner", self.learner, LEARNERS)
        if self.samples_per_tick < 1:
            raise InvalidArgumentError(
                f"invalid samples_per_tick {self.samples_per_tick!r}; valid: >= 1")
        ticks_per_step = -(-self.batch_size // self.samples_per_tick)
        if self.learner == "numba" and ticks_per_step > self.update_every:
            raise InvalidArgumentError(
                f"invalid samples_per_tick {self.samples_per_tick!r}; valid: >= batch_size / "
                f"update_every = {self.batch_size}/{self.update_every} (a step must end before "
                "the next one starts)")
        check_positive("learning_rate", self.learning_rate)
        check_positive("surprise_open_n", self.surprise_open_n)
        check_positive("surprise_release_n", self.surprise_release_n, allow_zero=True)
        check_positive("slow_rate_max", self.slow_rate_max)
        if self.surprise_release_n > self.surprise_open_n:
            raise InvalidArgumentError(
                f"invalid surprise_release_n {self.surprise_release_n!r}; "
                f"valid: 0 <= release <= surprise_open_n ({self.surprise_open_n})"
            )
