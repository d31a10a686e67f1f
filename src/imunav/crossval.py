"""Grouped cross-validation: the one way imunav tunes a default.

A default tuned on recordings and scored on the same recordings reports an
in-sample figure, which is optimistic. Every tuner in imunav (the attitude
parameter grid, the ZUPT detector thresholds, the LSTM training) therefore
scores its choice *out of fold*: the items (trials) are split into groups that
generalise (a recording session, a subject, a trial), each group is held out in
turn, the choice is made on the other groups only, and the held-out items are
scored with it (leave-one-group-out, Hastie, Tibshirani & Friedman, *The
Elements of Statistical Learning*, 2nd ed., §7.10; grouping as in
scikit-learn's ``LeaveOneGroupOut``).

Two entry points share one result type, :class:`CvResult`:

* :func:`select_by_cv` for tuners that can score every candidate on every item
  up front (a score matrix of shape ``(n_candidates, n_items)``, lower is
  better): in each fold the candidate with the lowest mean training score is
  chosen and the held-out items are scored with it.
* :func:`cross_validate` for tuners that fit a model (``fit(train_indices)``)
  and score it on the held-out items (``evaluate(model, test_indices)``).

Both also report the in-sample figure (choice made on all items, scored on the
same items) beside the out-of-fold one, to show the gap; only the out-of-fold
figure estimates what a user sees on recordings the default never saw.

:func:`pyshoe_session` gives the session of a pyshoe VICON trial (the date in
its file name); :func:`leave_one_group_out` the folds.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Hashable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.results import Result

__all__ = ["Fold", "CvResult", "leave_one_group_out", "select_by_cv", "cross_validate", "pyshoe_session"]

Array = NDArray[np.float64]
_DATE = re.compile(r"(\d{4}-\d{2}-\d{2})")


def pyshoe_session(name: str | Path) -> str:
    """Recording session of a pyshoe VICON trial: the date in its file name.

    ``2017-11-22-11-22-03.mat`` → ``"2017-11-22"``.  Trials of one day share
    the subject, the shoe mounting and the lab set-up, so they are held out
    together (data set: B. Wagstaff, V. Peretroukhin, J. Kelly, "Robust data-driven zero-velocity
    detection for foot-mounted inertial navigation", IEEE Sensors J. 20(2), 2020).

    Parameters
    ----------
    name : str or pathlib.Path
        File name or path of the trial.

    Returns
    -------
    str
        The session, ``"YYYY-MM-DD"``.

    Raises
    ------
    InvalidInputError
        If the name holds no date ``YYYY-MM-DD``.
    """
    m = _DATE.search(Path(str(name)).name)
    if m is None:
        raise InvalidInputError(
            f"cannot tell the session of trial {str(name)!r}: its name has no date YYYY-MM-DD; "
            "give the groups explicitly"
        )
    return m.group(1)


@dataclass(frozen=True)
class Fold:
    """One fold: the held-out ``group`` and the item indices on each side.

    Attributes
    ----------
    group : hashable
        The group held out in this fold.
    train : numpy.ndarray of int
        Indices of the items the choice is made on (every other group).
    test : numpy.ndarray of int
        Indices of the held-out items (the group's).
    """

    group: Hashable
    train: NDArray[np.int64]
    test: NDArray[np.int64]


def leave_one_group_out(groups: Sequence[Hashable]) -> list[Fold]:
    """Folds that hold out one group at a time, in order of first appearance.

    Parameters
    ----------
    groups : sequence of hashable
        Group of each item (e.g. :func:`pyshoe_session` of each trial).

    Returns
    -------
    list of Fold
        One fold per distinct group.

    Raises
    ------
    InsufficientDataError
        With no items, or fewer than two groups (nothing would be left to train on).
    """
    g = list(groups)
    if len(g) == 0:
        raise InsufficientDataError("cross-validation needs at least one item per group; got no items")
    order = list(dict.fromkeys(g))
    if len(order) < 2:
        raise InsufficientDataError(
            f"leave-one-group-out needs at least 2 groups; every item is in group {order[0]!r}"
        )
    idx = np.arange(len(g))
    lab = np.array([order.index(x) for x in g])
    return [Fold(grp, idx[lab != k], idx[lab == k]) for k, grp in enumerate(order)]


@dataclass(frozen=True)
class CvResult(Result):
    """Out-of-fold and in-sample scores of one tuning procedure.

    Attributes
    ----------
    items : tuple of str
        Names of the items (trials), in input order.
    groups : tuple of hashable
        Group of each item.
    oof : numpy.ndarray, shape (n_items,)
        Score of each item under the choice made without its group.
    fold_choice : dict
        The choice of each fold, keyed by held-out group (candidate
        index for :func:`select_by_cv`, whatever ``describe(model)`` returned for
        :func:`cross_validate`).
    in_sample : numpy.ndarray, shape (n_items,), or None
        Score of each item under the choice made on all items, or None when not computed.
    in_sample_choice : object
        That choice.
    extra : dict
        Free-form further results a tuner attaches (not part of :meth:`to_dict`).
    """

    items: tuple[str, ...]
    groups: tuple[Hashable, ...]
    oof: Array
    fold_choice: dict[Hashable, Any]
    in_sample: Array | None = None
    in_sample_choice: Any = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def oof_mean(self) -> float:
        """Mean out-of-fold score over items."""
        return float(np.mean(self.oof))

    @property
    def in_sample_mean(self) -> float | None:
        """Mean in-sample score over items (None when not computed)."""
        return None if self.in_sample is None else float(np.mean(self.in_sample))

    def per_group(self) -> dict[Hashable, float]:
        """Mean out-of-fold score of each group.

        Returns
        -------
        dict
            Group -> mean out-of-fold score of its items, in order of first appearance.
        """
        g = np.array([str(x) for x in self.groups])
        return {k: float(np.mean(self.oof[g == str(k)])) for k in dict.fromkeys(self.groups)}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (strict JSON: non-finite scores become None).

        Returns
        -------
        dict
            ``oof_mean``, ``in_sample_mean``, ``items`` (item, group, oof, in_sample), ``per_group``,
            ``fold_choice`` and ``in_sample_choice``.
        """

        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            "oof_mean": num(self.oof_mean),
            "in_sample_mean": None if self.in_sample is None else num(float(np.mean(self.in_sample))),
            "items": [
                {"item": it, "group": str(gr), "oof": num(o),
                 "in_sample": None if self.in_sample is None else num(self.in_sample[i])}
                for i, (it, gr, o) in enumerate(zip(self.items, self.groups, self.oof))
            ],
            "per_group": {str(k): num(v) for k, v in self.per_group().items()},
            "fold_choice": {str(k): _plain(v) for k, v in self.fold_choice.items()},
            "in_sample_choice": _plain(self.in_sample_choice),
        }


def _plain(v: Any) -> Any:
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return v


def _names(items: Sequence[str] | None, n: int) -> tuple[str, ...]:
    if items is None:
        return tuple(str(i) for i in range(n))
    if len(items) != n:
        raise ShapeError(f"{len(items)} item names for {n} items; give one name per item")
    return tuple(str(x) for x in items)


def select_by_cv(scores: ArrayLike, groups: Sequence[Hashable], *, items: Sequence[str] | None = None
                 ) -> CvResult:
    """Choose among candidates by leave-one-group-out CV on a score matrix.

    Parameters
    ----------
    scores : array_like
        (n_candidates, n_items) score of each candidate on each item, lower
        is better (e.g. total attitude RMSE, 2-D position error).
    groups : sequence of hashable
        Group of each item (e.g. :func:`pyshoe_session` of each trial).
    items : sequence of str, optional
        Item names, for the report.

    Returns
    -------
    CvResult
        ``fold_choice[g]`` is the index of the candidate with the lowest mean
        score over the items outside group g (ties: the first); ``oof[i]`` is
        item i's score under its fold's choice; ``in_sample_choice`` is the
        candidate with the lowest mean over all items, the one to ship.

    Raises
    ------
    ShapeError
        If ``scores`` is not (n_candidates, n_items) with one column per group entry.
    NonFiniteError
        If a score is NaN or infinite (every candidate must score every item).
    InsufficientDataError
        With fewer than two groups.
    """
    S = np.asarray(scores, dtype=float)
    if S.ndim == 1:
        S = S[None, :]
    if S.ndim != 2 or S.shape[1] != len(groups):
        raise ShapeError(f"scores must be (n_candidates, n_items={len(groups)}); got {np.shape(scores)}")
    if not np.all(np.isfinite(S)):
        bad = np.argwhere(~np.isfinite(S))[:5].tolist()
        raise NonFiniteError(f"non-finite scores at (candidate, item) {bad}; every candidate must score every item")
    folds = leave_one_group_out(groups)
    oof = np.empty(S.shape[1])
    choice: dict[Hashable, Any] = {}
    for f in folds:
        j = int(np.argmin(S[:, f.train].mean(axis=1)))
        choice[f.group] = j
        oof[f.test] = S[j, f.test]
    j_all = int(np.argmin(S.mean(axis=1)))
    return CvResult(_names(items, S.shape[1]), tuple(groups), oof, choice, S[j_all].copy(), j_all)


def cross_validate(fit: Callable[[NDArray[np.int64]], Any],
                   evaluate: Callable[[Any, NDArray[np.int64]], ArrayLike],
                   groups: Sequence[Hashable], *, items: Sequence[str] | None = None,
                   describe: Callable[[Any], Any] | None = None, in_sample: bool = False,
                   progress: Callable[[int, int, Hashable], None] | None = None) -> CvResult:
    """Leave-one-group-out CV of a fitting procedure.

    For each group g: ``model = fit(items outside g)``, then ``oof[g's items] = evaluate(model, g's items)``
    (Hastie, Tibshirani & Friedman 2009, §7.10).

    Parameters
    ----------
    fit : callable
        ``fit(train_indices) -> model``; must use only those items.
    evaluate : callable
        ``evaluate(model, test_indices) -> scores`` (one per test item, lower is better).
    groups : sequence of hashable
        Group of each item.
    items : sequence of str, optional
        Item names, for the report (default: their indices).
    describe : callable, optional
        What to record of each fold's model (default: nothing).
    in_sample : bool
        Also fit on all items and score every item (the in-sample
        figure, to show the gap; costs one more fit).
    progress : callable, optional
        Called as ``progress(k, n_folds, held_out_group)`` before each fit.

    Returns
    -------
    CvResult
        Out-of-fold scores, each fold's ``describe(model)``, and the in-sample scores when asked.

    Raises
    ------
    InsufficientDataError
        With fewer than two groups.
    ShapeError
        If ``evaluate`` returns a number of scores other than the number of held-out items, or ``items``
        has the wrong length.
    """
    folds = leave_one_group_out(groups)
    n = len(groups)
    oof = np.full(n, np.nan)
    choice: dict[Hashable, Any] = {}
    for k, f in enumerate(folds):
        if progress is not None:
            progress(k, len(folds), f.group)
        model = fit(f.train)
        s = np.asarray(evaluate(model, f.test), dtype=float).reshape(-1)
        if s.size != f.test.size:
            raise ShapeError(f"evaluate returned {s.size} scores for {f.test.size} held-out items")
        oof[f.test] = s
        choice[f.group] = describe(model) if describe is not None else None
    ins, ins_choice = None, None
    if in_sample:
        allidx = np.arange(n)
        model = fit(allidx)
        ins = np.asarray(evaluate(model, allidx), dtype=float).reshape(-1)
        ins_choice = describe(model) if describe is not None else None
    return CvResult(_names(items, n), tuple(groups), oof, choice, ins, ins_choice)
