"""Where the learned rows' rounding came from: batch size, thread count and memory alignment.

Run ``python -m impact_experiments.dp_numerics``. It prints, for the shipped Hammer
Vanilla checkpoint, whether one env's denoised actions are bit-identical

- when the env is denoised inside batches of 1 to 20 (at three positions) versus inside a
  batch of 24 (the earlier batched inference), and under ``batch_invariant`` (alone);
- with one versus two torch threads (same batch);
- with the input tensors at 1 to 8 floats of offset from their allocation (alignment);

and, for the internal model's SGD step (NumPy + OpenBLAS), whether 50 steps give the same
weights with 1 or 2 OpenBLAS threads (fresh processes) and with inputs at 0 to 16 floats of
offset. The answers are this machine's (CPU, library builds); docs/results.md quotes them.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys

import numpy as np
import torch

from impact_envs.policies.diffusion.model import denoise
from impact_envs.policies.diffusion.policy import DiffusionPolicy

SGD_SNIPPET = """
import hashlib, numpy as np
from impact_control.internal_model.model import InternalModel
from impact_control.internal_model.net import sgd_step
rng = np.random.default_rng(0)
m = InternalModel(); w, b = m._weights, m._biases
for _ in range(50):
    x = rng.standard_normal((16, m.input_dim)).astype(np.float32)
    y = (0.3 * rng.standard_normal((16, 6))).astype(np.float32)
    sgd_step(w, b, x, y, np.ones((16, 6), np.float32), 0.1)
print(hashlib.sha256(b"".join(a.tobytes() for a in (*w, *b))).hexdigest()[:16])
"""


def _policy() -> DiffusionPolicy:
    from impact_eval.methods import checkpoint_dir

    return DiffusionPolicy.load(checkpoint_dir("IMPACT/Hammer-v1", "vanilla"))


def batch_rows(policy: DiffusionPolicy, n: int = 24) -> list[str]:
    """Per batch size: how many rows equal the same rows denoised in a batch of ``n``."""
    d = policy.normalizer.obs.dim
    gen = torch.Generator().manual_seed(1)
    obs = torch.randn(n, policy.cfg.n_obs_steps, d, generator=gen)
    noise = torch.randn(n, policy.cfg.horizon, 10, generator=gen)
    lines = []
    with torch.inference_mode():
        ref = denoise(policy.net, policy.scheduler, obs, noise)
        alone = torch.cat([denoise(policy.net, policy.scheduler, obs[i:i + 1], noise[i:i + 1])
                           for i in range(n)])
        for b in range(1, 21):
            equal = []
            for start in sorted({0, 3, n - b}):
                r = denoise(policy.net, policy.scheduler, obs[start:start + b],
                            noise[start:start + b])
                equal.append(sum(torch.equal(r[i], ref[start + i]) for i in range(b)))
            lines.append(f"batch {b:2d}: rows equal to the batch of {n}: {equal} of {b} "
                         f"(positions 0, 3, {n - b})")
        lines.append(f"alone (batch of 1, what the policy computes) vs batch of {n}: "
                     f"{sum(torch.equal(alone[i], ref[i]) for i in range(n))} of {n} rows equal")
    return lines


def thread_and_alignment(policy: DiffusionPolicy) -> list[str]:
    """One env: 1 vs 2 torch threads; inputs at 1-8 floats of offset."""
    d = policy.normalizer.obs.dim
    gen = torch.Generator().manual_seed(2)
    obs = torch.randn(1, policy.cfg.n_obs_steps, d, generator=gen)
    noise = torch.randn(1, policy.cfg.horizon, 10, generator=gen)
    before = torch.get_num_threads()
    results = {}
    with torch.inference_mode():
        for threads in (1, 2):
            torch.set_num_threads(threads)
            results[threads] = denoise(policy.net, policy.scheduler, obs, noise)
        torch.set_num_threads(1)
        shifted = []
        for off in range(1, 9):
            bo = torch.empty(obs.numel() + off)
            bo[off:] = obs.flatten()
            bn = torch.empty(noise.numel() + off)
            bn[off:] = noise.flatten()
            r = denoise(policy.net, policy.scheduler, bo[off:].view(obs.shape),
                        bn[off:].view(noise.shape))
            shifted.append(torch.equal(r, results[1]))
    torch.set_num_threads(before)
    diff = float((results[1] - results[2]).abs().max())
    return [f"1 vs 2 torch threads, batch of 1: equal {torch.equal(results[1], results[2])} "
            f"(max |difference| {diff:.2e})",
            f"inputs offset by 1..8 floats: equal {shifted}"]


def sgd_lines() -> list[str]:
    """Internal-model SGD: OpenBLAS 1 vs 2 threads (fresh processes), input offsets."""
    digests = {}
    for threads in ("1", "2"):
        env = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads}
        out = subprocess.run([sys.executable, "-c", SGD_SNIPPET], capture_output=True,
                             text=True, env=env, check=True)
        digests[threads] = out.stdout.strip()
    from impact_control.internal_model.model import InternalModel
    from impact_control.internal_model.net import sgd_step

    rng = np.random.default_rng(0)
    batches = [(rng.standard_normal((16, 768)).astype(np.float32),
                (0.3 * rng.standard_normal((16, 6))).astype(np.float32)) for _ in range(50)]
    hashes = set()
    for off in range(17):
        m = InternalModel()
        for x, y in batches:
            buf = np.empty(x.size + off, np.float32)
            xv = buf[off:].reshape(x.shape)
            xv[:] = x
            sgd_step(m._weights, m._biases, xv, y, np.ones((16, 6), np.float32), 0.1)
        hashes.add(hashlib.sha256(b"".join(a.tobytes() for a in (*m._weights, *m._biases)))
                   .hexdigest())
    return [f"SGD, 50 steps, OpenBLAS 1 vs 2 threads: weights {digests['1']} / {digests['2']} "
            f"(equal {digests['1'] == digests['2']})",
            f"SGD, inputs offset by 0..16 floats: {len(hashes)} distinct result(s)"]


def main() -> int:
    """Print the measurements."""
    torch.set_num_threads(1)
    policy = _policy()
    for line in [*batch_rows(policy), *thread_and_alignment(policy), *sgd_lines()]:
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
