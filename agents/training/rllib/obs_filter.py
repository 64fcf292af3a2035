"""Observation normalisation for the RLlib backend (``normalize:`` in its YAML): the env-to-module connector
the env runners apply, its statistics as data for ``evaluate``, and the two ways back to a normaliser.

RLlib's ``MeanStdFilter`` (ray 2.60) keeps Welford running statistics (count, mean, sum of squared
deviations) per env runner; after every training iteration the algorithm merges the remote runners' states
into the local runner's and broadcasts the result. Its ``merge_states`` reads each runner's ``*_delta``
fields as the statistics of the samples since the last sync, but after a broadcast they hold the change of
the runner's *running* mean (reset to the local runner's zeros), not the mean of the new samples: from the
second iteration on, every merge pulls the mean towards zero (halved after two iterations with two runners,
~1/iterations later) and inflates the variance. :class:`ObsMeanStdFilter` is that connector with the merge
done from what each runner's state does hold exactly: its full statistics and the count it was synced at,
minus the statistics it was synced to (the local runner's before the merge).

Statistics live in RLlib's checkpoint (``env_runner/env_to_module_connector/ObsMeanStdFilter/``, pickled;
restored by ``Algorithm.restore_from_path`` on ``--resume`` and broadcast to the runners) and, as data, in
``srenv_policy.json`` (``obs_normalizer``: count, mean, std, clip_std), which ``evaluate`` reads without
``--trust-model``. The env runners import this module (the connector's class), so on a cluster every node
needs the repository's ``agents`` package importable, as well as srenv.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
import tree
from ray.rllib.connectors.env_to_module import MeanStdFilter
from ray.rllib.utils.filter import RunningStat


def _since_sync(remote: RunningStat, base: RunningStat) -> RunningStat:
    """The statistics of the samples ``remote`` pushed since it was last synced to ``base``.

    ``num_pushes - num_pushes_delta`` is the count the runner was synced at: 0 for a runner that never was
    (the first iteration, or a restarted runner) - then all its samples are new - else its state started
    from ``base`` and Chan's combination formula is inverted to take ``base`` out.
    """
    synced_at = remote.num_pushes - remote.num_pushes_delta
    n0, m0, s0 = (base.num_pushes, base.mean_array, base.sum_sq_diff_array) if synced_at else (0, 0.0, 0.0)
    n = remote.num_pushes
    new = RunningStat(remote.shape)
    if n - n0 <= 0:
        return new
    nb = n - n0
    mean = (n * remote.mean_array - n0 * m0) / nb
    m2 = np.maximum(remote.sum_sq_diff_array - s0 - n0 * nb / n * (m0 - mean) ** 2, 0.0)
    new.num_pushes = new.num_pushes_delta = nb
    new.mean_array, new.mean_delta_array = mean, np.copy(mean)
    new.sum_sq_diff_array, new.sum_sq_diff_delta_array = m2, np.copy(m2)
    return new


class ObsMeanStdFilter(MeanStdFilter):
    """RLlib's ``MeanStdFilter`` with the env runners' statistics merged exactly (see the module docstring)."""

    def merge_states(self, states: list[dict[str, Any]]) -> dict[str, Any]:
        if self._filters is None:
            self._init_new_filters()
        for agent_id, agent_filter in self._filters.items():
            local = tree.flatten(agent_filter.running_stats)
            base = [rs.copy() for rs in local]  # what every runner was broadcast after the last merge
            for state in states:
                remote = [RunningStat.from_state(s) for s in state[agent_id]["running_stats"]]
                for rs, b, r in zip(local, base, remote, strict=True):
                    rs.update(_since_sync(r, b))
        return self._get_state_from_filters(self._filters)


def _build_filter(clip_std: float, env: Any = None, spaces: Any = None, device: Any = None) -> ObsMeanStdFilter:
    """``AlgorithmConfig.env_runners(env_to_module_connector=...)``'s signature: (env, spaces, device)."""
    return ObsMeanStdFilter(clip_by_value=float(clip_std))


def connector_factory(clip_std: float) -> Any:
    """What the env runners call to build their normaliser (a partial of a module-level function pickles by
    reference)."""
    return partial(_build_filter, clip_std)


def _filter_state(algo: Any) -> dict[str, Any] | None:
    """The (merged) normaliser state of the algorithm's local env runner, None when there is none."""
    from ray.rllib.core import COMPONENT_ENV_TO_MODULE_CONNECTOR

    if algo.env_runner is not None:
        pipeline = algo.env_runner.get_state(components=[COMPONENT_ENV_TO_MODULE_CONNECTOR])
        pipeline = pipeline.get(COMPONENT_ENV_TO_MODULE_CONNECTOR, {})
    else:
        pipeline = algo.env_to_module_connector.get_state()
    return pipeline.get(ObsMeanStdFilter.__name__)


def export_stats(algo: Any) -> dict[str, Any] | None:
    """The normaliser as plain data for ``srenv_policy.json`` (None when ``normalize`` is off)."""
    state = _filter_state(algo)
    if state is None:
        return None
    agent = state[None]
    (stats,) = [RunningStat.from_state(s) for s in agent["running_stats"]]  # a Box observation: one stat
    return {"count": int(stats.n), "mean": np.asarray(stats.mean, dtype=np.float64).tolist(),
            "std": np.asarray(stats.std, dtype=np.float32).tolist(), "clip_std": float(agent["clip_by_value"])}
