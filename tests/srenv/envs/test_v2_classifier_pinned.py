"""srenv/SuckerRod-v2's observation carries the card classifier's probabilities, so v2 reads run 2's model, pinned
as package data (``srenv/models/classifier_run2.npz``), while ``srenv classify`` ships a later run's (run 7's,
docs/conditions.md): v2 keeps its numbers."""

from __future__ import annotations

import hashlib

import numpy as np

from srenv.analysis.card_classifier import DEFAULT_MODEL, V2_MODEL, CardClassifier
from srenv.analysis.card_shape import features
from srenv.envs.sucker_rod_v2 import SuckerRodV2Env, default_classifier
from srenv.physics.conditions import LABELS

RUN2_SHA256 = "627670e1bfc6e0b77d502da4d0996d6a58abae05f888e345aa4750bced4cca17"  # run 2's classifier.npz


def _probs(path, trace) -> np.ndarray:
    clf = CardClassifier.load(path)
    f = features(trace["polished_rod_position_m"], trace["polished_rod_load_n"])
    return np.asarray(clf.proba_features(f[None, :])[0])[[clf.labels.index(k) for k in LABELS]]


def test_the_pinned_file_is_run_2s_and_not_the_classify_default() -> None:
    assert hashlib.sha256(V2_MODEL.read_bytes()).hexdigest() == RUN2_SHA256
    assert V2_MODEL.read_bytes() != DEFAULT_MODEL.read_bytes()


def test_v2s_observation_uses_the_pinned_model() -> None:
    env = SuckerRodV2Env(event_rate_scale=0.0)
    env.reset(seed=3)
    obs, *_ = env.step(np.array([1.0, 1.0], np.float32))
    probs = obs[len(env.obs_names) - len(LABELS):]
    trace = env._last.trace
    pinned, shipped = _probs(V2_MODEL, trace), _probs(DEFAULT_MODEL, trace)
    np.testing.assert_array_equal(probs, pinned.astype(np.float32))
    np.testing.assert_array_equal(np.asarray(default_classifier()(trace), np.float32), pinned.astype(np.float32))
    assert not np.allclose(probs, shipped, atol=1e-4)  # the card tells the two models apart
