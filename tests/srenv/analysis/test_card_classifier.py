"""The classifier's model file holds one network or an ensemble (run 10, docs/conditions.md): an ensemble's
probabilities are the mean of its members'; a one-member file (every file shipped before run 10) reads as before,
bit for bit; a broken member axis is refused."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import run_on_avx2_numpy

from srenv.analysis.card_classifier import (
    DEFAULT_MODEL,
    MAX_MEMBERS,
    MEMBERS,
    BadModel,
    CardClassifier,
    members_of,
    stack_members,
)
from srenv.task.card_set import write_npz

# each shipped one-member file's probabilities on the eight CC0 plate cards' feature rows (a 66th entry 0.5 where the
# model reads one), measured with the code before run 10 (commit ae237c7): unchanged bit for bit
PINNED = {
    "classifier.npz": "0e60dba5f5c087643cce6a6b8aa73c6cb77e0a77eb365fd25ade07a040ce40ea",
    "classifier_config.npz": "17f6663a96a9e035d8feaae17f89e33cce9d8aab7d2aef2a34890452a5f30a3f",
    "classifier_pump.npz": "a5320db595108d0fae438ebdb0e7e46472d8079462b6ac5f610b4fefaa97076a",
    "classifier_pump_level.npz": "856d643979c709db81abc5d7d5cfed6a83643dcf89284a38915f3876b936f302",
    "classifier_pump_p3.npz": "a933644d7ed3503d663b3a12c21f72620a63f33ae145f9b8b9dd6dff198e5502",
    "classifier_run2.npz": "560fd6d97bc7d4f57f29f4511b1bbe447c4f7a4a4d24aa64d7d56d20488f3f0a",
    "classifier_run5.npz": "445891484d25c62a8c66a5116118bb9e43801199805c92995663ad96869b339a",
    # v3's pinned copy of run 7 (the shipped classifier.npz when v3 was made): the same probabilities
    "classifier_run7.npz": "0e60dba5f5c087643cce6a6b8aa73c6cb77e0a77eb365fd25ade07a040ce40ea",
}
DIGESTS = """
import hashlib, json
import numpy as np
from srenv.analysis.card_classifier import DEFAULT_MODEL, CardClassifier
from srenv.analysis.card_shape import features
cards = json.loads(open("tests/data/plate_reference_cards.json").read())["cards"]
out = {}
for name in NAMES:
    clf = CardClassifier.load(DEFAULT_MODEL.with_name(name))
    rows = np.array([features(np.asarray(c["position"], float), np.asarray(c["load"], float), clf.card_type)
                     for _, c in sorted(cards.items())])
    if clf.mean.shape[0] > rows.shape[1]:
        rows = np.c_[rows, np.full(len(rows), 0.5)]
    out[name] = hashlib.sha256(clf.proba_features(rows).tobytes()).hexdigest()
print(json.dumps(out))
"""


def _arrays(path) -> dict:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _rows(n: int = 6) -> np.ndarray:
    clf = CardClassifier.load(DEFAULT_MODEL.with_name("classifier_run5.npz"))
    return clf.mean + clf.std * np.random.default_rng(0).standard_normal((n, len(clf.mean)))


def test_the_shipped_one_member_files_read_as_before_bit_for_bit() -> None:
    got = json.loads(run_on_avx2_numpy(f"NAMES = {sorted(PINNED)!r}" + DIGESTS))
    assert got == PINNED


def test_an_ensemble_file_is_the_mean_of_its_members(tmp_path) -> None:
    a, b = (_arrays(DEFAULT_MODEL.with_name(n)) for n in ("classifier.npz", "classifier_run5.npz"))
    write_npz(str(tmp_path / "e.npz"), stack_members([a, b]))
    ens = CardClassifier.load(tmp_path / "e.npz")
    assert len(ens.members) == 2 and _arrays(tmp_path / "e.npz")[MEMBERS].tolist() == [2]
    f = _rows()
    pa, pb = (CardClassifier.from_weights(w).proba_features(f) for w in (a, b))
    np.testing.assert_array_equal(ens.proba_features(f), np.mean([pa, pb], axis=0))
    assert not np.allclose(pa, pb, atol=1e-3)  # the two members differ: the mean is not one of them


def test_a_one_member_list_is_the_file_itself_and_an_axis_of_one_reads_the_same(tmp_path) -> None:
    a = _arrays(DEFAULT_MODEL.with_name("classifier_run5.npz"))
    assert stack_members([a]) is a and members_of(a) == [a]
    axis = {k: (v if k == "labels" else v[None]) for k, v in a.items()}
    write_npz(str(tmp_path / "one.npz"), {**axis, MEMBERS: np.array(1)})
    f = _rows()
    np.testing.assert_array_equal(CardClassifier.load(tmp_path / "one.npz").proba_features(f),
                                  CardClassifier.from_weights(a).proba_features(f))


def _ensemble(**change) -> dict:
    a = _arrays(DEFAULT_MODEL.with_name("classifier_run5.npz"))
    return {**stack_members([a, a]), **change}


@pytest.mark.parametrize("change, what", [
    ({MEMBERS: np.array(0)}, f"members = 0, expected an integer in [1, {MAX_MEMBERS}]"),
    ({MEMBERS: np.array(MAX_MEMBERS + 1)}, "expected an integer in [1"),
    ({MEMBERS: np.array(2.0)}, "members = 2.0"),
    ({MEMBERS: np.array([2, 2])}, "members = [2, 2]"),
    ({MEMBERS: np.array("two")}, "members = 'two'"),
    ({MEMBERS: np.array(3)}, "expected a leading member axis of 3"),
])
def test_a_broken_member_axis_is_refused_in_one_message(change, what) -> None:
    with pytest.raises(BadModel, match="model file") as exc:
        CardClassifier.from_weights(_ensemble(**change))
    assert what in str(exc.value) and "\n" not in str(exc.value)


def test_one_member_of_an_ensemble_with_a_bad_layer_is_named() -> None:
    e = _ensemble()
    w0 = e["w0"].copy()
    w0[1, 0, 0] = np.nan
    with pytest.raises(BadModel, match=r"\(member 1\): layer 0 holds values that are not finite"):
        CardClassifier.from_weights({**e, "w0": w0})
