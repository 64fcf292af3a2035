"""The Ray RLlib backend (``backend: rllib``): its YAML (:mod:`.config`), the run (:mod:`.backend`), its
checkpoints (:mod:`.checkpoints`), the observation filter (:mod:`.obs_filter`) and srenv's ids in Ray's
registry (:mod:`.registry`). Ray is imported only by the modules that need it at run time."""
