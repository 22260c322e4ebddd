"""Inference cost of the Diffusion Policy per env step (batched DDIM, amortized over Ta).

Usage::

    python -m impact_experiments.dp_inference_cost [--checkpoint DIR] [--batch 32] \
        [--threads 1] [--train] [--env IMPACT/Hammer-v1]

It also measures the env's own step cost in the same run and prints the ratio.

``measure_inference`` is the function to call next to the env step cost: it runs ``act`` on
random observations for whole replanning cycles and reports the mean cost.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from dataclasses import dataclass

import numpy as np
import torch

from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.model import make_network
from impact_envs.policies.diffusion.normalizer import AffineMap, Normalizer
from impact_envs.policies.diffusion.policy import DiffusionPolicy

DEFAULT_OBS_DIMS = {
    "ee_pos": 3,
    "ee_rot6d": 6,
    "gripper_width": 1,
    "object_pos": 3,
    "object_rot6d": 6,
    "goal_pos": 3,
}


@dataclass(frozen=True)
class InferenceCost:
    """Measured policy cost.

    Attributes:
        batch_size: Envs per ``act`` call.
        ms_per_replan: One batched DDIM prediction for all envs [ms].
        ms_per_batched_step: Mean ``act`` call, amortized over Ta steps [ms].
        ms_per_env_step: ``ms_per_batched_step / batch_size`` [ms].
    """

    batch_size: int
    ms_per_replan: float
    ms_per_batched_step: float
    ms_per_env_step: float


def random_policy(cfg: DiffusionConfig | None = None, seed: int = 0) -> DiffusionPolicy:
    """Untrained policy with identity normalization (same cost as a trained one)."""
    cfg = cfg or DiffusionConfig()
    obs_dims = {k: DEFAULT_OBS_DIMS.get(k, 3) for k in cfg.obs_keys}
    obs_dim = sum(obs_dims.values())
    torch.manual_seed(seed)
    net = make_network(cfg, obs_dim)

    def identity(dim: int) -> AffineMap:
        return AffineMap(torch.ones(dim), torch.zeros(dim))

    return DiffusionPolicy(cfg, net, Normalizer(identity(obs_dim), identity(10)), obs_dims)


def measure_inference(
    policy: DiffusionPolicy, batch_size: int = 32, cycles: int = 3
) -> InferenceCost:
    """CPU time of ``cycles`` replanning cycles (Ta ``act`` calls each) after one warm-up
    cycle (process CPU time: meaningful with ``torch.set_num_threads(1)``)."""
    rng = np.random.default_rng(0)
    dims = policy.obs_dims
    policy.reset(batch_size)
    ta = policy.cfg.n_action_steps

    def obs() -> dict[str, np.ndarray]:
        return {k: rng.uniform(-1, 1, (batch_size, d)).astype(np.float32) for k, d in dims.items()}

    for _ in range(ta):
        policy.act(obs())
    step_times = []
    for _ in range(cycles * ta):
        batch = obs()
        start = time.process_time()  # CPU time: steadier on a shared machine
        policy.act(batch)
        step_times.append(time.process_time() - start)
    replans = np.asarray(step_times).reshape(cycles, ta)[:, 0]
    per_step = 1e3 * float(np.mean(step_times))
    return InferenceCost(
        batch_size, 1e3 * float(np.median(replans)), per_step, per_step / batch_size
    )


def measure_env_step(env_id: str, controller: str = "impact", steps: int = 90,
                     seed: int = 0) -> float:
    """Mean CPU milliseconds of one ``env.step`` (33-34 physics ticks with the controller),
    driven by the scripted expert from reset (the expert's own cost excluded)."""
    import gymnasium as gym

    import impact_envs  # noqa: F401 - registers the env ids
    from impact_control.policy import stack_obs
    from impact_envs.policies.experts import make_expert

    env = gym.make(env_id, controller=controller)
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    total = 0.0
    for _ in range(steps):
        action = expert.act(stack_obs([obs]))[0]
        start = time.process_time()
        obs, *_ = env.step(action)
        total += time.process_time() - start
    env.close()
    return 1e3 * total / steps


def measure_train_step(cfg: DiffusionConfig | None = None, steps: int = 5) -> float:
    """Median seconds of one AdamW step (forward, backward, optimizer, EMA) at
    ``cfg.batch_size`` on random data, after one warm-up step."""
    from impact_envs.policies.diffusion.model import diffusion_loss, make_train_scheduler
    from impact_learn.ema import EMA

    cfg = cfg or DiffusionConfig()
    obs_dim = sum(DEFAULT_OBS_DIMS.get(k, 3) for k in cfg.obs_keys)
    net = make_network(cfg, obs_dim)
    ema, scheduler = EMA(net), make_train_scheduler(cfg)
    optimizer = torch.optim.AdamW(net.parameters(), lr=cfg.lr, betas=cfg.betas)
    generator = torch.Generator().manual_seed(0)
    obs = torch.randn(cfg.batch_size, cfg.n_obs_steps, obs_dim, generator=generator)
    actions = torch.randn(cfg.batch_size, cfg.horizon, 10, generator=generator).clamp(-1, 1)
    times = []
    for _ in range(steps + 1):
        start = time.perf_counter()
        loss = diffusion_loss(net, scheduler, obs, actions, generator)
        optimizer.zero_grad(set_to_none=True)
        loss.backward()
        optimizer.step()
        ema.update(net)
        times.append(time.perf_counter() - start)
    return float(np.median(times[1:]))


def main(argv: list[str] | None = None) -> None:
    """Print the inference cost of a checkpoint (or an untrained default-size policy)."""
    parser = argparse.ArgumentParser(description="Diffusion Policy inference cost")
    parser.add_argument("--checkpoint", help="policy folder (default: untrained default net)")
    parser.add_argument("--batch", type=int, default=32, help="envs per act call")
    parser.add_argument("--cycles", type=int, default=3, help="timed replanning cycles")
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    parser.add_argument("--train", action="store_true", help="also time training steps")
    parser.add_argument("--env", default="IMPACT/Hammer-v1",
                        help="env whose step cost is measured in the same run ('' skips)")
    args = parser.parse_args(argv)
    torch.set_num_threads(args.threads)
    policy = DiffusionPolicy.load(args.checkpoint) if args.checkpoint else random_policy()
    cost = measure_inference(policy, args.batch, args.cycles)
    cfg = policy.cfg
    print(
        f"DDIM-{cfg.num_inference_steps}, Tp={cfg.horizon}, Ta={cfg.n_action_steps}, "
        f"down_dims={cfg.down_dims}, batch={cost.batch_size}, threads={args.threads}"
    )
    print(f"  replan (one batched DDIM call): {cost.ms_per_replan:8.2f} ms")
    print(f"  per batched env step (÷Ta):     {cost.ms_per_batched_step:8.2f} ms")
    print(f"  per single env step (÷Ta÷B):    {cost.ms_per_env_step:8.3f} ms")
    if args.env:
        env_ms = measure_env_step(args.env)
        print(f"  {args.env} env.step (IMPACT controller, CPU time): {env_ms:8.3f} ms")
        print(f"  policy cost / env cost:         {cost.ms_per_env_step / env_ms:8.1%}")
    if args.train:
        for batch in (64, 256):
            seconds = measure_train_step(dataclasses.replace(cfg, batch_size=batch))
            print(f"  train step at batch {batch}:        {seconds:8.3f} s")


if __name__ == "__main__":
    main()
