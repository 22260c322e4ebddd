"""The project's experiments: one-off reproduction and measurement scripts, outside the
library. Each module is run as ``python -m impact_experiments.<name>`` (the payload-adaptation
protocol also as ``impact-protocol``); docs/ cites the command beside every number it made.

This package imports the library (``impact_control``, ``impact_envs``, ``impact_learn``,
``impact_eval``, ``impact_franka``) and is imported by none of it
(``tests/test_architecture.py``): a measurement may be deleted or rewritten without touching
what users call. Among them: the payload-adaptation protocol (``adaptation.py``), the physics
acceptance checks (``physics.py``), per-episode traces (``trace.py``), cost benches
(``controller_cost.py``, ``dp_inference_cost.py``, ``crossing_cost.py``), and the
HammerBasket analyses (``authors_figure.py``, ``demo_sink.py``, ``policy_sink.py``,
``contact_paired.py``)."""
