"""Grouped cross-validation helper: folds, selection and the in-sample / out-of-fold gap."""

import json

import numpy as np
import pytest

from imunav.crossval import cross_validate, leave_one_group_out, pyshoe_session, select_by_cv
from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError


def test_pyshoe_session_is_the_date():
    assert pyshoe_session("2017-11-22-11-22-03.mat") == "2017-11-22"
    assert pyshoe_session("/x/y/2018-02-09-11-16-53.mat") == "2018-02-09"
    with pytest.raises(InvalidInputError, match="no date"):
        pyshoe_session("walk.mat")


def test_folds_hold_out_whole_groups():
    groups = ["a", "b", "a", "c", "b", "a"]
    folds = leave_one_group_out(groups)
    assert [f.group for f in folds] == ["a", "b", "c"]
    for f in folds:
        assert set(f.test) == {i for i, g in enumerate(groups) if g == f.group}
        assert set(f.train) | set(f.test) == set(range(6)) and not set(f.train) & set(f.test)
    with pytest.raises(InsufficientDataError, match="at least 2 groups"):
        leave_one_group_out(["a", "a"])


def test_select_by_cv_hand_computed():
    # candidate 0 is best on groups a and b, candidate 1 only on c, which dominates the overall mean
    S = np.array([[1.0, 1.0, 9.0], [2.0, 2.0, 0.0]])
    r = select_by_cv(S, ["a", "b", "c"], items=["t1", "t2", "t3"])
    # hold out a: train b,c -> means (5, 1) -> cand 1 -> 2.0; hold out b: same -> 2.0;
    # hold out c: train a,b -> (1, 2) -> cand 0 -> 9.0
    assert r.fold_choice == {"a": 1, "b": 1, "c": 0}
    np.testing.assert_array_equal(r.oof, [2.0, 2.0, 9.0])
    assert r.in_sample_choice == 1 and r.in_sample_mean == pytest.approx(4 / 3)
    assert r.oof_mean == pytest.approx(13 / 3)  # the in-sample figure hides a gap of 3
    assert r.per_group() == {"a": 2.0, "b": 2.0, "c": 9.0}
    d = json.loads(json.dumps(r.to_dict(), allow_nan=False))
    assert d["items"][2] == {"item": "t3", "group": "c", "oof": 9.0, "in_sample": 0.0}


def test_select_by_cv_rejects_bad_scores():
    with pytest.raises(ShapeError):
        select_by_cv(np.ones((2, 3)), ["a", "b"])
    with pytest.raises(NonFiniteError, match="candidate, item"):
        select_by_cv(np.array([[1.0, np.nan]]), ["a", "b"])


def test_select_by_cv_optimism_on_noise():
    """Pure-noise candidates: the in-sample minimum is biased low, the out-of-fold mean is not."""
    rng = np.random.default_rng(1)
    gaps = []
    for _ in range(200):
        S = rng.normal(size=(50, 12))
        r = select_by_cv(S, np.repeat(np.arange(6), 2))
        gaps.append(r.oof_mean - r.in_sample_mean)
    # E[in-sample min of 50 means of 12 N(0,1)] = -2.25/sqrt(12) = -0.65; out-of-fold is unbiased (0)
    assert np.mean(gaps) > 0.5


def test_cross_validate_never_shows_a_model_its_test_group():
    groups = ["s1"] * 3 + ["s2"] * 2 + ["s3"] * 4
    x = np.arange(9.0)

    def fit(train):
        return {"train": set(train.tolist()), "mean": x[train].mean()}

    def evaluate(model, test):
        # a fold model never sees its held-out items; only the in-sample model (trained on all) does
        assert len(model["train"]) == 9 or not model["train"] & set(test.tolist())
        return np.abs(x[test] - model["mean"])

    r = cross_validate(fit, evaluate, groups, describe=lambda m: round(m["mean"], 3), in_sample=True)
    assert r.fold_choice == {"s1": round(x[3:].mean(), 3), "s2": round(np.r_[x[:3], x[5:]].mean(), 3),
                             "s3": round(x[:5].mean(), 3)}
    np.testing.assert_allclose(r.oof[:3], np.abs(x[:3] - x[3:].mean()))
    np.testing.assert_allclose(r.in_sample, np.abs(x - x.mean()))
    with pytest.raises(ShapeError, match="2 scores for 3"):
        cross_validate(fit, lambda m, t: [0.0, 0.0], groups)
