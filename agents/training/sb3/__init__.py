"""The Stable-Baselines3 backend: :func:`.train.train` from a :class:`agents.training.config.TrainConfig`."""
