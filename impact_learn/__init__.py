"""Learning from demonstrations, outside the runtime package: record scripted-expert
demonstrations (``impact-collect``, ``collect.py``) into a zarr store (``dataset.py``) and
train a Diffusion Policy on them (``impact-train``, ``train.py``) that
``impact_envs.policies.diffusion.DiffusionPolicy`` loads.

The functions ``train.train`` and ``collect.collect`` share their module's name, so import
them from the modules::

    from impact_learn.train import RunOptions, train
    from impact_learn.collect import collect
    from impact_learn.collect_config import CollectConfig
"""

from impact_envs import _gl  # noqa: F401 - the headless GL backend before mujoco loads
