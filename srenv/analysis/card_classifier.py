"""The condition classifier at inference: a small MLP whose weights are data (an NPZ read without pickle).

The model file (``srenv/models/classifier.npz``, written by ``python -m srenv.tools.train_classifier``)
holds ``labels``, the feature scaling ``mean``/``std`` and layers ``w0, b0, w1, b1, ...`` (ReLU between,
softmax at the end), and since run P1 optionally ``card_type`` (``surface`` or ``pump``: the card it reads; a file
without it is a surface model, as every file before), since run P2 optionally ``feature_set`` (``shape+level``: the
pump card's 65th entry is its load level against a described well's fluid load, so the model needs a config; a file
without it is ``shape``, read as before), since run P3 ``shape+level+offset`` (a 66th entry: the lower plateau
against the described P+), since run 9 for a surface model ``shape+midline`` (a 66th entry: the surface card's load
midline against the described well, srenv.analysis.surface_level; ``srenv classify --config`` only). Since run 10 a
file may hold an ensemble: ``members`` (an integer, 1..MAX_MEMBERS) and every array but ``labels``, ``card_type`` and
``feature_set`` with a leading member axis of that length; the model's probabilities are the mean of the members'. A
file without ``members`` is one member and reads as every file before. Trained on simulated cards only
(docs/conditions.md).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from ..errors import ConfigError, short_repr
from ..input_files import open_regular
from ..physics.conditions import LABELS
from .card_shape import CARD_TYPES, N_FEATURES, features
from .pump_level import FEATURE_SETS, with_level, with_offset
from .surface_level import FEATURE_SET as MIDLINE
from .surface_level import with_midline

DEFAULT_MODEL = Path(__file__).resolve().parents[1] / "models" / "classifier.npz"
# run 2's weights, pinned: srenv/SuckerRod-v2's observation carries its probabilities, so v2 keeps its numbers
# whatever model ``srenv classify`` ships (docs/conditions.md, run 4)
V2_MODEL = DEFAULT_MODEL.with_name("classifier_run2.npz")
# run 7's weights (the shipped model when v3 was made), pinned the same way for srenv/SuckerRod-v3
V3_MODEL = DEFAULT_MODEL.with_name("classifier_run7.npz")
# the pump (downhole) card model of run P1 (`srenv classify --card pump`)
PUMP_MODEL = DEFAULT_MODEL.with_name("classifier_pump.npz")
# run P2's pump model with the load level (`srenv classify --config WELL --card pump`), if shipped
PUMP_LEVEL_MODEL = DEFAULT_MODEL.with_name("classifier_pump_level.npz")
# run P3's pump model with the level and the offset, trained on diagnosed cards (the default with a config), if shipped
PUMP_P3_MODEL = DEFAULT_MODEL.with_name("classifier_pump_p3.npz")
# run 9's surface model with the load midline (`srenv classify --config WELL`, surface cards only), if shipped
CONFIG_MODEL = DEFAULT_MODEL.with_name("classifier_config.npz")
# the feature sets a model file of each card type may hold (absent = shape)
ALLOWED_FEATURE_SETS = {"surface": (FEATURE_SETS[0], MIDLINE), "pump": FEATURE_SETS}
MAX_LAYERS = 8
MAX_WIDTH = 4096
MAX_MEMBERS = 16  # an ensemble's members in one file (run 10: 5); the inference time grows with them
MEMBERS = "members"  # the ensemble file's member count; absent: one member without the axis
SHARED = ("labels", "card_type", "feature_set", MEMBERS)  # an ensemble file's entries without the member axis


class BadModel(ValueError):
    """A model file that is not a classifier of this shape (or not data at all)."""


def card_type_of_file(data: dict) -> str:
    """The model file's card type: one string (stored as a one-item array), absent = surface (files before P1)."""
    return _one_string(data, "card_type", "surface")


def _one_string(data: dict, key: str, absent: str) -> str:
    """A one-item string array entry of a model file; ``absent`` if the file has none."""
    if key not in data:
        return absent
    v = data[key]
    return str(v.reshape(-1)[0]) if v.size == 1 and v.dtype.kind == "U" else repr(v.tolist())


def feature_set_of_file(data: dict) -> str:
    """The model file's feature set, absent = shape (files before P2)."""
    return _one_string(data, "feature_set", FEATURE_SETS[0])


def members_of(data: dict) -> list[dict]:
    """A model file's members, each a dict of one member's arrays (a file without ``members``: itself, as before);
    raises BadModel's message (ValueError) for a count out of range or an array without the member axis."""
    if MEMBERS not in data:
        return [data]
    v = data[MEMBERS]
    k = int(v.reshape(-1)[0]) if v.size == 1 and v.dtype.kind in "iu" else 0  # one item (write_npz: shape (1,))
    if not 1 <= k <= MAX_MEMBERS:
        raise ValueError(f"members = {short_repr(v.tolist(), 40)}, expected an integer in [1, {MAX_MEMBERS}]")
    for key, a in data.items():
        if key not in SHARED and (a.ndim < 1 or a.shape[0] != k):
            raise ValueError(f"array {key} has shape {a.shape}, expected a leading member axis of {k} (members)")
    return [{key: a if key in SHARED else a[i] for key, a in data.items() if key != MEMBERS} for i in range(k)]


def stack_members(members: list[dict]) -> dict:
    """One model file's arrays from the members' weights (trainer dicts of one shape); one member: its own dict,
    unchanged (the file every run before 10 wrote)."""
    if len(members) == 1:
        return members[0]
    first = members[0]
    out = {k: np.stack([m[k] for m in members]) for k in first if k not in SHARED}
    return {**out, **{k: first[k] for k in SHARED if k in first}, MEMBERS: np.array(len(members))}


def _member_proba(f: np.ndarray, mean: np.ndarray, std: np.ndarray, layers: list) -> np.ndarray:
    """One member's class probabilities of feature rows (n, n_features)."""
    h = (np.atleast_2d(f) - mean) / std
    for i, (w, b) in enumerate(layers):
        h = h @ w + b
        if i < len(layers) - 1:
            h = np.maximum(h, 0.0)
    h = h - h.max(axis=1, keepdims=True)
    e = np.exp(h)
    return e / e.sum(axis=1, keepdims=True)


def _layers(data: dict) -> tuple[np.ndarray, np.ndarray, list]:
    """(mean, std, layers) of one member's arrays; raises KeyError for a missing one."""
    mean, std = data["mean"].astype(np.float64), data["std"].astype(np.float64)
    layers = []
    for i in range(MAX_LAYERS):
        if f"w{i}" not in data:
            break
        layers.append((data[f"w{i}"].astype(np.float64), data[f"b{i}"].astype(np.float64)))
    return mean, std, layers


class CardClassifier:
    def __init__(self, labels: tuple[str, ...], mean: np.ndarray, std: np.ndarray, layers: list,
                 card_type: str = "surface", feature_set: str = FEATURE_SETS[0], more_members: tuple = ()):
        """One member's (mean, std, layers); ``more_members``: the ensemble's others, each (mean, std, layers)."""
        self.labels, self.card_type, self.feature_set = labels, card_type, feature_set
        self.members = ((mean, std, layers), *more_members)

    @property
    def mean(self) -> np.ndarray:
        """The first member's feature means (every member's features have the same width)."""
        return self.members[0][0]

    @property
    def std(self) -> np.ndarray:
        return self.members[0][1]

    @property
    def layers(self) -> list:
        return self.members[0][2]

    @property
    def needs_config(self) -> bool:
        """True: the model reads the card against a described well (level, offset or midline): a config is needed."""
        return self.feature_set != FEATURE_SETS[0]

    @property
    def needs_level(self) -> bool:
        """True: the model reads the pump card's load level, so a well config (its described fluid load) is needed."""
        return self.feature_set in FEATURE_SETS[1:]

    @property
    def needs_offset(self) -> bool:
        """True: the model reads the offset (run P3), so the described P+ is needed too."""
        return self.feature_set == FEATURE_SETS[2]

    @classmethod
    def load(cls, path: str | Path = DEFAULT_MODEL) -> CardClassifier:
        try:  # a regular file (a FIFO would block np.load), read as arrays only
            with open_regular(path, "--model", "model file") as fh, np.load(fh, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except ConfigError as exc:
            raise BadModel(f"model file {path}: {exc.expected}") from None
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise BadModel(f"model file {path}: not a readable NPZ of arrays ({exc})") from None
        return cls.from_weights(data, path)

    @classmethod
    def from_weights(cls, data: dict, path: str | Path = "(in memory)", n_features: int | None = None) -> CardClassifier:
        """The classifier of a model file's arrays (one member or an ensemble), checked; raises BadModel.
        ``n_features``: the feature rows' width (the trainer's weights, before their file names a feature set);
        None: the file's feature set's."""
        try:
            labels = tuple(str(x) for x in data["labels"])
            card_type, feature_set = card_type_of_file(data), feature_set_of_file(data)
            members = [_layers(m) for m in members_of(data)]
        except KeyError as exc:
            raise BadModel(f"model file {path}: missing array {exc}") from None
        except ValueError as exc:
            raise BadModel(f"model file {path}: {exc}") from None
        if card_type not in CARD_TYPES:
            raise BadModel(f"model file {path}: card_type {card_type!r}, expected one of {CARD_TYPES}")
        if feature_set not in ALLOWED_FEATURE_SETS[card_type]:
            raise BadModel(f"model file {path}: feature_set {feature_set!r} with card_type {card_type!r}, expected "
                           f"one of {ALLOWED_FEATURE_SETS[card_type]}")
        if n_features is None:
            n_features = N_FEATURES + (feature_set in (FEATURE_SETS[2], MIDLINE))
        for i, m in enumerate(members):
            cls._check(path if len(members) == 1 else f"{path} (member {i})", labels, *m, n_features)
        return cls(labels, *members[0], card_type, feature_set, tuple(members[1:]))

    @staticmethod
    def _check(path, labels, mean, std, layers, n_features: int) -> None:
        if labels != LABELS:
            raise BadModel(f"model file {path}: labels {labels} are not srenv's twelve")
        if mean.shape != (n_features,) or std.shape != (n_features,) or not np.all(std > 0):
            raise BadModel(f"model file {path}: feature scaling of the wrong shape (expected {n_features})")
        width = n_features
        for i, (w, b) in enumerate(layers):
            if w.ndim != 2 or w.shape[0] != width or b.shape != (w.shape[1],) or w.shape[1] > MAX_WIDTH:
                raise BadModel(f"model file {path}: layer {i} has shape {w.shape}, expected ({width}, n)")
            if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
                raise BadModel(f"model file {path}: layer {i} holds values that are not finite")
            width = w.shape[1]
        if not layers or width != len(LABELS):
            raise BadModel(f"model file {path}: the last layer must give {len(LABELS)} outputs")

    def proba_features(self, f: np.ndarray) -> np.ndarray:
        """Class probabilities of feature rows (n, N_FEATURES): one member's, or the mean of an ensemble's."""
        if len(self.members) == 1:
            return _member_proba(f, *self.members[0])
        return np.mean([_member_proba(f, *m) for m in self.members], axis=0)

    def card_features(self, position, load, fluid_load_n: float | None = None,
                      downstroke_load_n: float | None = None) -> np.ndarray:
        """The model's features of one card (``fluid_load_n``: the described fluid load, N, for a level model;
        ``downstroke_load_n``: the described P+ as a true load, N, for an offset model, the described static
        polished-rod downstroke load for a midline model (surface_level.described_surface); ignored by the others);
        raises card_shape.BadCard, pump_level.BadLevel."""
        f = features(position, load, self.card_type)
        if not self.needs_config:
            return f
        if fluid_load_n is None or ((self.needs_offset or self.feature_set == MIDLINE) and downstroke_load_n is None):
            what = "pump's" if self.card_type == "pump" else "well's"
            raise ValueError(f"this model's features are {self.feature_set}: it needs the described {what} loads")
        if self.feature_set == MIDLINE:
            return with_midline(f, load, downstroke_load_n, fluid_load_n)
        f = with_level(f, load, fluid_load_n)
        return with_offset(f, load, downstroke_load_n, fluid_load_n) if self.needs_offset else f

    def classify(self, position, load, fluid_load_n: float | None = None,
                 downstroke_load_n: float | None = None) -> tuple[str, dict[str, float]]:
        """(label, probabilities of all twelve) of one card; raises card_shape.BadCard, pump_level.BadLevel."""
        p = self.proba_features(self.card_features(position, load, fluid_load_n, downstroke_load_n))[0]
        return self.labels[int(np.argmax(p))], {k: float(v) for k, v in zip(self.labels, p)}
