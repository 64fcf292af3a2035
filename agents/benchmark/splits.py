"""The benchmark YAML's three splits (``tuning``, ``validation``, ``test``): their keys, the scenarios each may
play, and their seeds resolved and checked pairwise disjoint before any work."""

from __future__ import annotations

from typing import Any

from srenv.errors import short_repr
from srenv.safe_yaml import yaml_kind

from ..inputs import seeds
from ..training.tuning import refuse_test_split
from .config_error import BenchmarkConfigError, Declared

# the three splits' blocks: a misspelt key (``scenaro: validation``) would silently play the default wells
SPLIT_KEYS: Declared = {"seeds": ((dict, list), "{start: S, count: N} or a list of seeds"),
                        "scenario": ((str,), ("the split's scenario (tuning: train; validation: train or "
                                              "validation; test: test or validation)"))}

TEST_SCENARIOS = ("test", "validation")
# the wells the validation stage (model selection) plays: the training wells on seeds of their own (every config
# before this key), or v2's validation split - wells no tuning or training ever drew, which is what predicts how a
# selected design does on the test and fresh wells (docs/agents.md, "Which wells a validation gate plays")
VALIDATION_SCENARIOS = ("train", "validation")


def has_validation_split(env_id: str) -> bool:
    """v2 and later have a validation split of their own wells (srenv.task.well_family.V2_SPLITS)."""
    version = str(env_id).rsplit("-v", 1)[-1]
    return version.isdigit() and int(version) >= 2


def check_splits(cfg: dict[str, Any]) -> dict[str, set[int]]:
    """The tuning, validation and test seeds, resolved in ``cfg`` and checked disjoint; their sets."""
    for part in ("tuning", "test"):
        if not isinstance(cfg.get(part), dict) or "seeds" not in cfg[part]:
            found = "missing" if part not in cfg else f"= {short_repr(cfg[part], 80)} ({yaml_kind(cfg[part])})"
            raise BenchmarkConfigError(f"benchmark config: {part} {found}: expected a mapping with seeds")
        cfg[part]["seeds"] = seeds(cfg[part]["seeds"], f"{part}.seeds")
    cfg["tuning"].setdefault("scenario", "train")
    refuse_test_split(cfg["tuning"]["scenario"], "tune")
    # the scenario the test stage plays: the held-out test split, or (the quick pipeline check, which must not
    # spend a look at the test split) v2's validation split
    cfg["test"].setdefault("scenario", "test")
    if cfg["test"]["scenario"] not in TEST_SCENARIOS:
        raise BenchmarkConfigError(f"benchmark config: test.scenario: {cfg['test']['scenario']!r}: expected one of "
                                   f"{', '.join(TEST_SCENARIOS)}")
    val = cfg.setdefault("validation", {"seeds": []})
    val["seeds"] = seeds(val["seeds"], "validation.seeds") if val.get("seeds") else []
    val.setdefault("scenario", "train")
    if val["scenario"] not in VALIDATION_SCENARIOS:
        raise BenchmarkConfigError(f"benchmark config: validation.scenario: {short_repr(val['scenario'], 40)}: "
                                   f"expected one of {', '.join(VALIDATION_SCENARIOS)}")
    if val["scenario"] == "validation" and not has_validation_split(cfg.get("env_id", "")):
        raise BenchmarkConfigError(f"benchmark config: validation.scenario: 'validation': expected 'train' for "
                                   f"{cfg.get('env_id')} (only v2 and later have a validation split)")
    sets = {"tuning": set(cfg["tuning"]["seeds"]), "validation": set(val["seeds"]), "test": set(cfg["test"]["seeds"])}
    for a, b in (("tuning", "test"), ("validation", "test"), ("tuning", "validation")):
        if sets[a] & sets[b]:
            raise BenchmarkConfigError(f"benchmark config: {a}.seeds and {b}.seeds share "
                                       f"{sorted(sets[a] & sets[b])[:5]}: expected disjoint seed sets")
    return sets
