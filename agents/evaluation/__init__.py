"""Running policies and reading models: one episode runner and its process pool (:mod:`.rollout`), policies
from specs and model files read as data (:mod:`.agent`, :mod:`.model_io`, :mod:`.normalizer`,
:mod:`.rllib_model`), v0's held-out evaluation (:mod:`.evaluate`) and the benchmark replay (:mod:`.replay`).
Above :mod:`agents.policies`; below :mod:`agents.training`, which tunes and distils through the rollout."""
