"""Visuomotor encoder (``impact_envs/policies/diffusion/vision.py``): shapes, spatial softmax,
determinism, random crops only in training, configuration errors."""

from __future__ import annotations

import time

import pytest
import torch

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import ImageEncoderConfig
from impact_envs.policies.diffusion.vision import (
    ImageEncoder,
    ObservationEncoder,
    SpatialSoftmax,
    crop,
)

CFG = ImageEncoderConfig(image_keys=("overview_rgb", "wrist_rgb"))


def _batch(b: int = 3, t: int = 2, size: int = 32, seed: int = 0) -> tuple[torch.Tensor, dict]:
    g = torch.Generator().manual_seed(seed)
    state = torch.randn(b, t, 5, generator=g)
    images = {k: torch.randint(0, 256, (b, t, size, size, 3), generator=g, dtype=torch.uint8)
              for k in CFG.image_keys}
    return state, images


def _encoder(seed: int = 0) -> ObservationEncoder:
    torch.manual_seed(seed)
    return ObservationEncoder(CFG, state_dim=5)


def test_shapes_and_state_passthrough():
    enc = _encoder().eval()
    state, images = _batch()
    out = enc(state, images)
    assert out.shape == (3, 2, 5 + 2 * CFG.feature_dim) == (3, 2, enc.out_dim)
    torch.testing.assert_close(out[..., :5], state)
    assert ImageEncoder(CFG)(torch.zeros(4, 3, 84, 84)).shape == (4, CFG.feature_dim)


def test_spatial_softmax_finds_the_hot_pixel():
    pool = SpatialSoftmax(1, 1)
    with torch.no_grad():
        pool.project.weight.fill_(1.0)
        pool.project.bias.zero_()
    maps = torch.zeros(1, 1, 5, 9)
    maps[0, 0, 4, 0] = 100.0  # bottom-left corner
    torch.testing.assert_close(pool(maps), torch.tensor([[-1.0, 1.0]]), atol=1e-4, rtol=0)


def test_crop_centre_and_random():
    x = torch.arange(2 * 3 * 6 * 8, dtype=torch.float32).reshape(2, 3, 6, 8)
    torch.testing.assert_close(crop(x, (4, 4), random=False), x[:, :, 1:5, 2:6])
    g = torch.Generator().manual_seed(1)
    out = crop(x, (4, 4), random=True, generator=g)
    assert out.shape == (2, 3, 4, 4)
    for i in range(2):  # each image's crop is a window of that image
        hits = [(r, c) for r in range(3) for c in range(5)
                if torch.equal(out[i], x[i, :, r:r + 4, c:c + 4])]
        assert len(hits) == 1


def test_determinism_and_crops_only_in_training():
    state, images = _batch()
    a, b = _encoder(0), _encoder(0)
    a.eval(), b.eval()
    torch.testing.assert_close(a(state, images), b(state, images), rtol=0, atol=0)
    g1 = torch.Generator().manual_seed(7)
    eval_out = a(state, images, g1)
    assert g1.initial_seed() == 7 and torch.equal(g1.get_state(),
                                                  torch.Generator().manual_seed(7).get_state())
    a.train()
    t1 = a(state, images, torch.Generator().manual_seed(7))
    t2 = a(state, images, torch.Generator().manual_seed(7))
    t3 = a(state, images, torch.Generator().manual_seed(8))
    torch.testing.assert_close(t1, t2, rtol=0, atol=0)
    assert not torch.allclose(t1, t3) and not torch.allclose(t1, eval_out)
    torch.testing.assert_close(a.eval()(state, images), eval_out, rtol=0, atol=0)


def test_gradients_reach_every_camera():
    enc = _encoder().train()
    state, images = _batch()
    enc(state, images, torch.Generator().manual_seed(0)).sum().backward()
    for key in CFG.image_keys:
        grads = [p.grad for p in enc.cameras[key].parameters()]
        assert all(g is not None and torch.isfinite(g).all() for g in grads)


def test_config_errors_are_one_line():
    for bad, match in (({"crop_ratio": 0.0}, "valid: 0 < crop_ratio <= 1"),
                       ({"n_groups": 3}, "divisor of every channel count"),
                       ({"image_keys": ()}, "valid: distinct keys"),
                       ({"keypoints": 0}, "valid: >= 1")):
        with pytest.raises(InvalidArgumentError, match=match):
            ImageEncoderConfig(**bad)
    with pytest.raises(InvalidArgumentError, match="missing image 'wrist_rgb'"):
        state, images = _batch()
        _encoder()(state, {"overview_rgb": images["overview_rgb"]})


def test_cost_of_a_training_batch_is_reported(capsys):
    """Forward + backward of 64 windows x 2 steps x 2 cameras at 96 x 96 (printed, not bounded:
    docs/diffusion_policy.md quotes a run of it)."""
    torch.set_num_threads(1)
    enc = _encoder().train()
    state, images = _batch(b=64, size=96)
    params = sum(p.numel() for p in enc.parameters())
    start = time.perf_counter()
    enc(state, images, torch.Generator().manual_seed(0)).sum().backward()
    print(f"encoder: {params} parameters, {time.perf_counter() - start:.2f} s per batch")
    assert params < 500_000
