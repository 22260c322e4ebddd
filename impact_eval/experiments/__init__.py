"""Experiments and measurements beside the sweep CLI: the payload-adaptation protocol
(``impact-protocol``, ``adaptation.py``), the physics acceptance checks (``physics.py``),
per-episode traces (``trace.py``), cost benches of the controller core (``controller_cost.py``)
and of Diffusion Policy inference (``dp_inference_cost.py``), and the demonstration analyses
(``demo_ambiguity.py``, ``demonstrator_gains.py``)."""
