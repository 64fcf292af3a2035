"""Training: the YAML schema (:mod:`.config`), the SB3 backend (:mod:`.sb3`), the RLlib backend
(:mod:`.rllib`), the training-only envs (:mod:`.shaping`, :mod:`.residual_env`), baseline tuning
(:mod:`.tuning`) and distillation (:mod:`.distill`). Torch, SB3 and Ray are imported where used."""
