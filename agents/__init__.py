"""Agents for ``srenv/SuckerRod-v0``: baseline controllers, Stable-Baselines3 training and evaluation.

- :mod:`agents.baselines` - ``RockingMachinePolicy`` (constant SPM and stroke, the unit as installed) and
  ``FillagePolicy`` (VSD pump-off control, PI on fillage), both with SB3's ``predict`` interface.
- :mod:`agents.train` - PPO / SAC from rl-zoo-style YAML (``python -m agents train CONFIG.yaml``).
- :mod:`agents.evaluate` - held-out-seed evaluation, comparison table and episode plots
  (``python -m agents evaluate --policy ...``).

For ``srenv/SuckerRod-v1`` (the field observation, a family of wells):

- :mod:`agents.baselines_v1` - ``installed``, ``best_constant``, ``pump_off``, ``fillage_pi`` and the
  ``oracle`` (perfect-model planner), SB3 ``predict`` interface.
- :mod:`agents.tuning` - reproducible tuning of those on training wells only (the test split is refused).
- :mod:`agents.residual_v1` - residual agents (a learned correction on a tuned baseline).
- :mod:`agents.rollout_v1` - episodes of any policy, in a small process pool.
- :mod:`agents.benchmark` - ``python -m agents benchmark CONFIG [--quick]`` and the quick start.

This package imports ``srenv``; ``srenv`` never imports it. The name ``agents`` is generic and may clash
with other installed packages: import it only from its CLI and the tests. Torch and SB3 are imported
lazily, so ``import agents`` stays light.
"""

from .baselines import FillagePolicy, RockingMachinePolicy, action_from_setpoints, setpoints_from_action

__all__ = ["FillagePolicy", "RockingMachinePolicy", "action_from_setpoints", "setpoints_from_action"]
