"""Agents for srenv's envs: baselines, training, evaluation and the v1 benchmark, in four layers.

From the ground up (each imports only those below it, and ``srenv``; ``srenv`` never imports this package):

- :mod:`agents.envs` - the env ids and one ``make_env``.
- :mod:`agents.policies` - the ``Policy`` protocol (SB3's ``predict``); v0's baselines, v1's field
  baselines and the oracle; the residual and ensemble wrappers of trained models.
- :mod:`agents.evaluation` - one episode runner (and its process pool), model files read as data,
  ``python -m agents evaluate`` (v0) and ``replay`` (a benchmark report's episodes, re-run).
- :mod:`agents.training` - SB3 and RLlib from a YAML (``python -m agents train``), reward shaping, the
  residual training env, baseline tuning on training wells only, distillation.
- :mod:`agents.benchmark` - ``python -m agents benchmark CONFIG [--quick]`` and the quick start.

:mod:`agents.cli` parses the command line. From a checkout the package is ``agents`` (``python -m
agents``); the wheel installs the same code as ``srenv_agents`` (command ``srenv-agents``), a name that
cannot clash with other packages called ``agents``. Its modules import each other relatively, so both
names work. Torch, SB3 and Ray are imported lazily: ``import agents`` stays light.
"""
