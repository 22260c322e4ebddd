"""torch's intra-op threads in a simulation process: one."""

from __future__ import annotations


def limit_torch_threads() -> None:
    """Set torch's intra-op threads to 1 when it has more (process-wide).

    Called when an env (or robosuite's IMPACT controller) is made, as the controller did
    itself while its internal model ran on torch: a diffusion policy's small batched network
    calls in the same process gain nothing from extra threads, which compete with the
    simulation for cores, and its numbers stay those of one thread.
    """
    import torch

    if torch.get_num_threads() > 1:
        torch.set_num_threads(1)
