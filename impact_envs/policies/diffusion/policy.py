"""``DiffusionPolicy``: batched receding-horizon rollout of a trained diffusion model.

Timing per env (To = 2, Tp = 16, Ta = 8)::

    step t:     |o_{t-1} o_t|                  observation history (first obs repeated)
    prediction: |a_{t-1} a_t a_{t+1} ... a_{t+14}|   Tp actions, index To-1 is "now"
    executed:         |a_t ... a_{t+7}|        Ta actions, one per ``act`` call

Every env whose action queue is empty is replanned by its own DDIM call (batch of one, one
torch thread). The initial noise of env i comes from its own generator, seeded by ``(seed, i)``
at ``reset`` or by ``(seed, episode seed)`` with ``seed_envs`` (DDIM with eta = 0 draws no
further noise). An env's actions are then bit-for-bit a function of its own observations and
seed: torch's CPU kernels round differently for different batch sizes and thread counts
(docs/results.md, "Reproducibility"), so a batched call would make a rollout depend on how many
other envs replanned with it, i.e. on ``--envs-per-worker``, the worker count and resumption.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import torch
from safetensors.torch import load_file, save_file

import impact_envs
from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.policy import ACTION_DIM
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.history import ObservationHistory
from impact_envs.policies.diffusion.inference import UNetForward, frozen_unet
from impact_envs.policies.diffusion.model import (
    DiffusionNet,
    denoise,
    encode,
    make_inference_scheduler,
    make_network,
)
from impact_envs.policies.diffusion.normalizer import ACTION_POS, Normalizer
from impact_envs.policies.diffusion.vision import VisuomotorNet

MODEL_FILE = "model.safetensors"
CONFIG_FILE = "config.json"
NORMALIZER_FILE = "normalizer.safetensors"
META_FILE = "meta.json"
CHECKPOINT_FORMAT = 1
GRIPPER_DIM = 9
"""Index of the gripper command (−1 open … +1 closed) in the 10-d action."""


@contextlib.contextmanager
def one_torch_thread() -> Iterator[None]:
    """Run the block with one torch intra-op thread, then restore the caller's count.

    The network's numerics depend on the thread count (reductions are split per thread), so
    the policy fixes it instead of inheriting whatever the calling process uses.
    """
    threads = torch.get_num_threads()
    if threads != 1:
        torch.set_num_threads(1)
    try:
        yield
    finally:
        if threads != 1:
            torch.set_num_threads(threads)


def env_generator(seed: int, *keys: int) -> torch.Generator:
    """Generator for policy seed ``seed`` and an env key (slot index or episode seed)."""
    state = np.random.SeedSequence([seed, *keys]).generate_state(1, dtype=np.uint64)[0]
    return torch.Generator().manual_seed(int(state))


class DiffusionPolicy:
    """Diffusion Policy (state-based, or visuomotor with ``cfg.vision``) implementing the
    ``Policy`` protocol.

    Args:
        cfg: Hyper-parameters (obs keys, To, Tp, Ta, DDIM steps, cameras).
        net: The (EMA) U-Net, or camera encoder + U-Net (``VisuomotorNet``).
        normalizer: Observation/action normalizer of the training set.
        obs_dims: ``{obs_key: d_key}`` for ``cfg.obs_keys`` (order given by ``cfg.obs_keys``).
        seed: Seed of the sampling noise; reapplied at every ``reset``.
        meta: Free-form JSON-serialisable training information (saved in meta.json).
        batch_invariant: True (default, and what impact-eval uses): every env is denoised
            alone, so its actions do not depend on which other envs replan with it. False:
            one batched DDIM call for all replanning envs, about 2-5x cheaper per env for
            5-20 envs but rounded differently for every batch size (results then depend on
            ``--envs-per-worker`` and on resumption; docs/results.md, "Reproducibility").
    """

    def __init__(
        self,
        cfg: DiffusionConfig,
        net: DiffusionNet,
        normalizer: Normalizer,
        obs_dims: Mapping[str, int],
        *,
        seed: int = 0,
        meta: Mapping[str, Any] | None = None,
        batch_invariant: bool = True,
    ) -> None:
        missing = [k for k in cfg.obs_keys if k not in obs_dims]
        if missing:
            raise InvalidArgumentError(f"obs_dims lacks keys {missing}; needs {cfg.obs_keys}")
        self.cfg = cfg
        self.net = net.eval()
        self.normalizer = normalizer
        self.obs_dims = {k: int(obs_dims[k]) for k in cfg.obs_keys}
        if normalizer.obs.dim != sum(self.obs_dims.values()):
            raise InvalidArgumentError("normalizer obs dim does not match obs_dims")
        self.seed = seed
        self.meta = dict(meta or {})
        self.batch_invariant = bool(batch_invariant)
        self.scheduler = make_inference_scheduler(cfg)
        self.n_envs = 0
        self._unet_one: UNetForward | None = None  # built at the first batch-of-one call

    def reset(self, n_envs: int) -> None:
        """Clear history and action queues of ``n_envs`` envs and reseed their noise."""
        if n_envs < 1:
            raise InvalidArgumentError(f"n_envs must be >= 1, got {n_envs}")
        cfg = self.cfg
        self.n_envs = n_envs
        image_keys = cfg.vision.image_keys if cfg.vision is not None else ()
        self._history = ObservationHistory(n_envs, cfg.n_obs_steps, self.normalizer.obs.dim,
                                           image_keys)
        self._queue = np.zeros((n_envs, cfg.n_action_steps, ACTION_DIM), dtype=np.float32)
        self._queue_pos = np.full(n_envs, cfg.n_action_steps)
        self._live = np.ones(n_envs, dtype=bool)
        self._generators = [env_generator(self.seed, i) for i in range(n_envs)]

    def seed_envs(self, episode_seeds: Sequence[int]) -> None:
        """Reseed env i's noise from ``(seed, episode_seeds[i])`` (call after ``reset``).

        An episode's actions then depend on its own seed only, not on its slot in the batch
        (impact-eval calls this with the paired episode seeds).
        """
        if len(episode_seeds) != self.n_envs:
            raise InvalidArgumentError(f"got {len(episode_seeds)} seeds for {self.n_envs} envs")
        self._generators = [env_generator(self.seed, 1 << 32, int(s)) for s in episode_seeds]

    def reset_envs(self, indices: np.ndarray | list[int]) -> None:
        """Start a new episode in envs ``indices`` only (their generators continue)."""
        self._history.mark_fresh(indices)
        self._live[indices] = True
        self._queue_pos[indices] = self.cfg.n_action_steps

    def finish_envs(self, indices: np.ndarray | list[int]) -> None:
        """Envs ``indices`` ended their episodes: sample no more chunks for them.

        Their rows of ``act`` then repeat their last action (the caller discards them), so a
        lockstep batch whose episodes end at different times pays the network only for the
        envs still running. ``reset`` / ``reset_envs`` make them live again.
        """
        self._live[indices] = False

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Return ``(B, 10)`` float32 actions for the batched observation ``obs``."""
        flat = self._flat_obs(obs)
        if self.n_envs != flat.shape[0]:
            if self.n_envs:
                raise InvalidArgumentError(f"got {flat.shape[0]} envs, reset was for {self.n_envs}")
            self.reset(flat.shape[0])
        self._history.push(flat, obs)
        steps = self.cfg.n_action_steps
        replan = np.flatnonzero((self._queue_pos >= steps) & self._live)
        if replan.size:
            self._queue[replan] = self.predict_chunk(replan)
            self._queue_pos[replan] = 0
        position = np.minimum(self._queue_pos, steps - 1)  # finished envs: last action
        actions = self._queue[np.arange(self.n_envs), position].copy()
        self._queue_pos = np.minimum(self._queue_pos + 1, steps)
        if self.cfg.action_xyz == "delta_measured":  # the offset meets this step's TCP
            actions[:, ACTION_POS] += np.asarray(obs["ee_pos"], dtype=np.float32)
        return actions

    def frames_read_next(self) -> np.ndarray:
        """``(n_envs,)`` bool: whether env ``i``'s next observation's images will be read
        (``FrameReadingPolicy``): it will when a replan comes within ``n_obs_steps`` calls of
        ``act``, for an env still running, in a visuomotor policy."""
        if self.cfg.vision is None or not self.n_envs:
            return np.zeros(self.n_envs, dtype=bool)
        calls_to_replan = np.maximum(self.cfg.n_action_steps - self._queue_pos, 0)
        return self._live & (calls_to_replan <= self.cfg.n_obs_steps - 1)

    def _flat_obs(self, obs: Mapping[str, np.ndarray]) -> torch.Tensor:
        missing = [k for k in self.cfg.obs_keys if k not in obs]
        if missing:
            raise InvalidArgumentError(
                f"observation lacks keys {missing}; needs {self.cfg.obs_keys}"
            )
        parts = [np.asarray(obs[k], dtype=np.float32) for k in self.cfg.obs_keys]
        parts = [p.reshape(p.shape[0], -1) for p in parts]
        return torch.from_numpy(np.concatenate(parts, axis=1))

    def predict_chunk(self, envs: np.ndarray) -> np.ndarray:
        """Sample and return the ``(len(envs), Ta, 10)`` actions to execute for ``envs``.

        Each env is denoised alone (batch of one, one thread) unless ``batch_invariant`` is
        False: see the module docstring.
        """
        with one_torch_thread(), torch.inference_mode():
            if self.batch_invariant:
                sample = torch.cat([self._denoise(np.array([i]), self._unet()) for i in envs])
            else:
                sample = self._denoise(envs, self.net)
        actions = self.normalizer.action.inverse(sample)
        # clip_sample keeps positions in the demos' range and rot6d in [-1, 1]; a gripper
        # channel that was constant in the demos can land a little outside [-1, 1]
        grip = actions[..., GRIPPER_DIM]
        if self.cfg.binary_gripper:
            actions[..., GRIPPER_DIM] = torch.where(grip > 0.0, 1.0, -1.0)
        else:
            grip.clamp_(-1.0, 1.0)
        start = self.cfg.n_obs_steps - 1
        return actions[:, start : start + self.cfg.n_action_steps].numpy().astype(np.float32)

    def _denoise(self, envs: np.ndarray, net: UNetForward) -> torch.Tensor:
        """Normalized ``(len(envs), Tp, 10)`` action sequences, one call, each env's noise."""
        shape = (self.cfg.horizon, ACTION_DIM)
        noise = torch.stack([torch.randn(shape, generator=self._generators[i]) for i in envs])
        rows = torch.as_tensor(envs)
        state = self.normalizer.obs.forward(self._history.state[rows])
        cond = encode(self.net, state, self._history.images_of(rows))  # eval: centre crops
        return denoise(net, self.scheduler, cond, noise)

    def _unet(self) -> UNetForward:
        """The batch-of-one network: frozen when that is bit-identical (inference.py)."""
        if self._unet_one is None:
            visuomotor = isinstance(self.net, VisuomotorNet)
            unet = self.net.unet if visuomotor else self.net
            step_dim = self.net.encoder.out_dim if visuomotor else self.normalizer.obs.dim
            cond_dim = self.cfg.n_obs_steps * step_dim
            self._unet_one = frozen_unet(unet, self.cfg.horizon, ACTION_DIM, cond_dim)
        return self._unet_one

    def save(self, directory: str | Path) -> None:
        """Write model.safetensors, config.json, normalizer.safetensors and meta.json."""
        path = Path(directory)
        path.mkdir(parents=True, exist_ok=True)
        state = {k: v.detach().cpu().contiguous() for k, v in self.net.state_dict().items()}
        save_file(state, str(path / MODEL_FILE))
        save_file(self.normalizer.state_dict(), str(path / NORMALIZER_FILE))
        self.cfg.to_json(path / CONFIG_FILE)
        meta = {
            **self.meta,
            "checkpoint_format": CHECKPOINT_FORMAT,
            "package_version": impact_envs.__version__,
            "obs_dims": self.obs_dims,
            "action_dim": ACTION_DIM,
        }
        (path / META_FILE).write_text(json.dumps(meta, indent=2) + "\n")

    @classmethod
    def load(
        cls, directory: str | Path, *, seed: int = 0, batch_invariant: bool = True
    ) -> DiffusionPolicy:
        """Load a checkpoint written by ``save``; raises CheckpointError if missing or corrupt.

        ``seed`` and ``batch_invariant`` as in the constructor.
        """
        path = Path(directory)
        for name in (MODEL_FILE, CONFIG_FILE, NORMALIZER_FILE, META_FILE):
            if not (path / name).is_file():
                raise CheckpointError(f"checkpoint {path} is missing {name}")
        try:
            cfg = DiffusionConfig.from_json(path / CONFIG_FILE)
            meta = json.loads((path / META_FILE).read_text())
            obs_dims = {k: int(meta["obs_dims"][k]) for k in cfg.obs_keys}
        except (ValueError, KeyError, TypeError) as exc:
            raise CheckpointError(f"checkpoint {path} has bad config/meta: {exc}") from None
        normalizer = Normalizer.from_state_dict(_read_tensors(path / NORMALIZER_FILE))
        net = make_network(cfg, sum(obs_dims.values()))
        try:
            net.load_state_dict(_read_tensors(path / MODEL_FILE), strict=True)
        except RuntimeError as exc:
            summary = str(exc).splitlines()[0]
            raise CheckpointError(f"{path / MODEL_FILE} does not match config: {summary}") from None
        try:
            return cls(cfg, net, normalizer, obs_dims, seed=seed, meta=meta,
                       batch_invariant=batch_invariant)
        except InvalidArgumentError as exc:
            raise CheckpointError(f"checkpoint {path} is inconsistent: {exc}") from None


def _read_tensors(path: Path) -> dict[str, torch.Tensor]:
    try:
        return load_file(str(path))
    except Exception as exc:  # safetensors raises several error types on corrupt files
        raise CheckpointError(f"cannot read {path}: {type(exc).__name__}") from None
