"""Leave-one-session-out cross-validation of the LSTM zero-velocity detector on the pyshoe VICON trials.

Protocol (issue 12, items 1 and 3), all through :mod:`imunav.crossval`:

* groups: the recording session of each trial (the date in its file name, 5 sessions);
* classical baseline: every detector x threshold of ``GRIDS`` scored on every
  trial (ZuptFilter with the default ZuptConfig, error_2d against VICON);
  :func:`select_by_cv` picks the single fixed (detector, threshold) on the
  training sessions and scores the held-out session with it (out of fold);
* LSTM: :func:`cross_validate` trains on the training sessions only: labels =
  the best stored classical labels of each training trial, the guard's SHOE
  threshold = the SHOE grid value with the smallest mean error over the
  training trials (:func:`imunav.learn.select_shoe_threshold`); the network
  settings are the :class:`LstmConfig` defaults, fixed before the CV.  One
  more fit on all trials gives the in-sample figure, printed beside.
* decision rule (which checks of the SHOE guard to apply, ``RULES``): every
  rule is scored on every trial with its out-of-fold probability, and
  :func:`select_by_cv` picks the rule of each fold on the other sessions.
  This is nested CV up to one shortcut: the other sessions' probabilities come
  from models whose training included the held-out session.  The figure
  reported for the LSTM is this selection's out-of-fold error; the in-sample
  choice is the shipped default.
* fast gait: every held-out trial is also replayed 1.5x and 2x faster
  (:func:`imunav.learn.time_warp`, attitude from the INS with the trial's
  SHOE flags) and scored with the fold's model and the fold's SHOE.

Acceptance: out-of-fold mean >= 25 % below the out-of-fold classical
baseline, out-of-fold worst trial <= the baseline's worst trial.

Run:  PYTHONPATH=src python benchmarks/bench_zupt_lstm_cv.py [--json out.json] [--save-model PATH]
(5 folds + 1 in-sample fit, about 1 min of training each on one CPU thread.)
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from imunav.crossval import cross_validate, pyshoe_session, select_by_cv
from imunav.ins import ZuptConfig, ZuptFilter, detector_statistic, error_2d
from imunav.io.datasets import shared_data_path
from imunav.io.foot import read_pyshoe_mat
from imunav.learn import (
    LstmConfig,
    LstmDetector,
    best_labels,
    gravity_in_body,
    time_warp,
    train_lstm,
)

GRIDS = {
    "shoe": np.geomspace(1e6, 1e9, 31),
    "ared": np.geomspace(0.01, 3.0, 31),
    "amvd": np.geomspace(1e-3, 2.0, 31),
    "mbgtd": np.geomspace(0.01, 1.0, 31),
}
SPEEDS = (1.5, 2.0)

#: decision rules on the LSTM probability (LstmConfig overrides): the guard's checks one at a time and together,
#: with and without the gait prior.
#: Chosen per fold by select_by_cv on the out-of-fold probabilities; the shipped default is the in-sample choice.
RULES = {
    "no guard": {"guard": False},
    "ratio gate 0.5 (default)": {},
    "ratio gate 0.25": {"guard_min_ratio": 0.25},
    "fill missed": {"guard_min_ratio": 0.0, "guard_fill_s": 0.1},
    "bridge split": {"guard_min_ratio": 0.0, "guard_bridge_s": 0.1},
    "count gate": {"guard_min_ratio": 0.0, "guard_max_count_ratio": 1.5},
    "all checks": {"guard_fill_s": 0.1, "guard_bridge_s": 0.1, "guard_max_count_ratio": 1.5},
    "ratio gate 0.5, no gait prior": {"max_gap_s": None},
    "no guard, no gait prior": {"guard": False, "max_gap_s": None},
}


def _err(tr, zv, cfg) -> float:
    return error_2d(ZuptFilter(cfg).run(tr.imu, zv).position, tr.position)


def _train_key(train_names, cfg) -> str:
    """Cache key of a training run: the training trials and the settings that affect training."""
    d = {k: v for k, v in cfg.to_dict().items() if not k.startswith("guard") and k != "shoe_threshold"}
    return hashlib.sha1(json.dumps([list(train_names), d]).encode()).hexdigest()[:16]


def _warped(tr, factor: float):
    """The trial replayed ``factor`` times faster: ImuData-like object and its reference."""
    from imunav.timeseries import ImuData

    shoe = detector_statistic(tr.imu, "shoe") < 1e8
    x = np.concatenate([tr.imu.accel, tr.imu.gyro], axis=1)
    w, u = time_warp(x, gravity_in_body(tr.imu, shoe), factor)
    ref = np.stack([np.interp(u, np.arange(len(tr.position)), tr.position[:, k]) for k in range(3)], axis=1)
    return ImuData(tr.imu.t[:w.shape[0]], w[:, 3:], w[:, :3]), ref


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--json", default=None)
    ap.add_argument("--save-model", default=None, help="write the in-sample model (all trials) here")
    ap.add_argument("--set", action="append", default=[], help="LstmConfig override key=value (experiments only)")
    ap.add_argument("--no-fast", action="store_true", help="skip the time-compressed replays")
    ap.add_argument("--cache", default=None, help="folder for the trained models: reused when present "
                    "(same training trials and settings), written otherwise")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    root = shared_data_path("foot", "pyshoe_vicon")
    if root is None:
        raise SystemExit("shared data foot/pyshoe_vicon not found (set IMUNAV_DATA)")
    files = sorted(root.glob("*.mat"))
    trials = [read_pyshoe_mat(f) for f in files]
    names = [t.name for t in trials]
    groups = [pyshoe_session(f) for f in files]
    cfg_ins = ZuptConfig()
    out: dict = {"n_trials": len(trials), "sessions": sorted(set(groups))}
    t0 = time.perf_counter()

    # --- classical: every (detector, threshold) on every trial; LOSO choice of one fixed pair
    cand, S = [], []
    shoe_T = [detector_statistic(t.imu, "shoe") for t in trials]
    for det, grid in GRIDS.items():
        Ts = shoe_T if det == "shoe" else [detector_statistic(t.imu, det) for t in trials]
        for g in grid:
            cand.append((det, float(g)))
            S.append([_err(t, T < g, cfg_ins) for t, T in zip(trials, Ts)])
    S = np.array(S)
    base = select_by_cv(S, groups, items=names)
    base_choice = {str(k): cand[v] for k, v in base.fold_choice.items()}
    print(f"classical scores: {S.shape[0]} candidates x {S.shape[1]} trials in {time.perf_counter() - t0:.0f} s")
    print(f"best fixed classical, chosen per fold: {base_choice}; on all trials: {cand[base.in_sample_choice]}")
    n_shoe = GRIDS["shoe"].size
    out["classical"] = {**base.to_dict(), "fold_choice": base_choice, "in_sample_choice": cand[base.in_sample_choice]}

    # --- LSTM labels (best stored classical labels per trial; used only when the trial is in a training fold)
    labels = [best_labels(t)[0] for t in trials]
    over = {}
    for kv in args.set:
        k, v = kv.split("=", 1)
        cur = getattr(LstmConfig(), k)
        over[k] = tuple(float(x) for x in v.split(",")) if isinstance(cur, tuple) else (
            v.lower() in ("1", "true") if isinstance(cur, bool) else type(cur)(v))
    rule_scores = np.full((len(RULES), len(trials)), np.nan)
    rule_scores_ins = np.full((len(RULES), len(trials)), np.nan)
    extra: dict = {"raw": np.full(len(trials), np.nan), "fallback_fraction": np.full(len(trials), np.nan),
                   "stance_lstm": np.full(len(trials), np.nan), "stance_shoe": np.full(len(trials), np.nan)}
    for f in SPEEDS:
        for k in ("lstm", "raw", "shoe"):
            extra[f"fast{f}_{k}"] = np.full(len(trials), np.nan)
            extra[f"fast{f}_stance_{k}"] = np.full(len(trials), np.nan)
    warped = {} if args.no_fast else {(i, f): _warped(t, f) for i, t in enumerate(trials) for f in SPEEDS}
    times: list = []
    models: list = []

    def fit(train):
        j = int(np.argmin(S[:n_shoe][:, train].mean(axis=1)))
        cfg = LstmConfig(**{**over, "shoe_threshold": float(GRIDS["shoe"][j])})
        t1 = time.perf_counter()
        path = Path(args.cache) / f"lstm-{_train_key([names[i] for i in train], cfg)}.npz" if args.cache else None
        if path is not None and path.is_file():
            model = LstmDetector.load(path)
            model.config = cfg  # the decision settings (guard) are not part of training
        else:
            model, _ = train_lstm([trials[i].imu for i in train], [labels[i] for i in train], cfg, threads=1)
            if path is not None:
                model.save(path)
        times.append(time.perf_counter() - t1)
        models.append(model)
        return model

    def evaluate(model, test):
        errs = []
        for i in test:
            tr = trials[i]
            p = model.probability(tr.imu)
            res = model.detect(tr.imu, probability=p)
            errs.append(_err(tr, res.zv, cfg_ins))
            into = rule_scores_ins if len(test) == len(trials) else rule_scores
            base_cfg = model.config
            for r, kw in enumerate(RULES.values()):
                model.config = replace(base_cfg, **kw)
                into[r, i] = _err(tr, model.detect(tr.imu, probability=p).zv, cfg_ins)
            model.config = base_cfg
            if len(test) == len(trials):
                continue  # the in-sample fit: no diagnostics
            extra["raw"][i] = _err(tr, model.detect(tr.imu, probability=p, guard=False).zv, cfg_ins)
            extra["fallback_fraction"][i] = res.params["guard"]["fallback_fraction"]
            extra["stance_lstm"][i] = res.stance_fraction
            extra["stance_shoe"][i] = float(np.mean(shoe_T[i] < model.config.shoe_threshold))
            for f in SPEEDS if warped else ():
                imu, ref = warped[(i, f)]
                pw = model.probability(imu)
                flags = {"lstm": model.detect(imu, probability=pw).zv,
                         "raw": model.detect(imu, probability=pw, guard=False).zv,
                         "shoe": detector_statistic(imu, "shoe") < model.config.shoe_threshold}
                for k, zv in flags.items():
                    extra[f"fast{f}_{k}"][i] = error_2d(ZuptFilter(cfg_ins).run(imu, zv).position, ref)
                    extra[f"fast{f}_stance_{k}"][i] = float(np.mean(zv))
        return errs

    def progress(k, n, g):
        print(f"fold {k + 1}/{n}: holding out session {g} ({groups.count(g)} trials)", flush=True)

    def describe(model):
        return {"shoe_threshold": model.config.shoe_threshold, "train_seconds": round(times[-1], 1)}

    cv = cross_validate(fit, evaluate, groups, items=names, describe=describe, in_sample=True, progress=progress)

    # --- the decision rule, chosen per fold on the other sessions' out-of-fold probabilities
    rules = select_by_cv(rule_scores, groups, items=names)
    rule_names = list(RULES)
    rule_choice = {str(k): rule_names[v] for k, v in rules.fold_choice.items()}
    shipped_rule = rule_names[rules.in_sample_choice]

    # --- report
    sel, b_oof, l_ins = rules.oof, base.oof, cv.in_sample
    print("\nper trial, 2-D error (m): LSTM out-of-fold (rule chosen per fold) | in-sample (shipped model and rule) | "
          "no guard out-of-fold | best fixed classical out-of-fold | stance fraction shipped rule / SHOE | "
          "share taken from SHOE")
    for i, n in enumerate(names):
        print(f"  {n} {groups[i]}  {sel[i]:7.3f} | {l_ins[i]:7.3f} | {extra['raw'][i]:7.3f} | {b_oof[i]:7.3f} | "
              f"{extra['stance_lstm'][i]:.2f} / {extra['stance_shoe'][i]:.2f} | {extra['fallback_fraction'][i]:.2f}")
    print("\nper session, mean 2-D error (m): LSTM out-of-fold | in-sample | no guard out-of-fold | classical "
          "out-of-fold | classical in-sample")
    gl, gb = rules.per_group(), base.per_group()
    for g in gl:
        m = np.array([x == g for x in groups])
        print(f"  {g} ({m.sum():2d} trials)  {gl[g]:.3f} | {np.mean(l_ins[m]):.3f} | {np.mean(extra['raw'][m]):.3f} | "
              f"{gb[g]:.3f} | {np.mean(base.in_sample[m]):.3f}")
    print("\ndecision rules, mean 2-D error (m) over the 42 trials: out-of-fold | in-sample (model on all trials)")
    for r, name in enumerate(rule_names):
        print(f"  {name:22s} {rule_scores[r].mean():.3f} (worst {rule_scores[r].max():.3f}) | "
              f"{rule_scores_ins[r].mean():.3f} (worst {rule_scores_ins[r].max():.3f})")
    print(f"rule chosen per fold: {rule_choice}; on all trials: {shipped_rule}"
          + ("" if RULES[shipped_rule] == {} else "  (WARNING: not the LstmConfig default the model ships with)"))
    ratio = rules.oof_mean / base.oof_mean
    print("\nmean 2-D error              out-of-fold   in-sample")
    print(f"  LSTM (shipped protocol)   {rules.oof_mean:8.3f} m  {cv.in_sample_mean:8.3f} m")
    print(f"  best fixed classical      {base.oof_mean:8.3f} m  {base.in_sample_mean:8.3f} m")
    print(f"worst trial: LSTM {sel.max():.3f} m ({names[int(np.argmax(sel))]}), classical {b_oof.max():.3f} m "
          f"({names[int(np.argmax(b_oof))]}); in-sample LSTM {l_ins.max():.3f} m, classical {base.in_sample.max():.3f} m")
    print(f"ratio LSTM / classical (out of fold): {ratio:.3f} -> reduction {100 * (1 - ratio):.1f} % "
          f"(>= 25 %: {'met' if ratio <= 0.75 else 'NOT met'}); worst trial "
          f"{'met' if sel.max() <= b_oof.max() else 'NOT met'}")
    if warped:
        print("\nfast gait (held-out trials replayed faster; fold models), mean 2-D error / mean stance fraction:")
        for f in SPEEDS:
            row = "  ".join(f"{k} {np.mean(extra[f'fast{f}_{k}']):.3f} m / {np.mean(extra[f'fast{f}_stance_{k}']):.2f}"
                            f" (worst {np.max(extra[f'fast{f}_{k}']):.2f})" for k in ("lstm", "raw", "shoe"))
            print(f"  x{f}: {row}")
    print(f"training time per fit: {', '.join(f'{t:.0f}' for t in times)} s (CPU, 1 thread; ~0 = from --cache); "
          f"total {time.perf_counter() - t0:.0f} s")
    out["lstm"] = {**rules.to_dict(), "fold_choice": rule_choice, "in_sample_choice": shipped_rule,
                   "in_sample_mean": cv.in_sample_mean,
                   "items": [{**it, "in_sample": float(l_ins[k])} for k, it in enumerate(rules.to_dict()["items"])],
                   "shoe_threshold_per_fold": {str(k): v for k, v in cv.fold_choice.items()},
                   "config": LstmConfig(**over).to_dict(), "train_seconds": times}
    out["rules"] = {name: {"oof": rule_scores[r].tolist(), "in_sample": rule_scores_ins[r].tolist(),
                           "settings": RULES[name]} for r, name in enumerate(rule_names)}
    out["extra"] = {k: v.tolist() for k, v in extra.items()}
    out["ratio_oof"] = ratio
    out["reduction_oof"] = 1 - ratio
    out["worst_oof"] = {"lstm": float(sel.max()), "classical": float(b_oof.max())}
    if args.save_model:
        # the in-sample fit (the last one) is the model to ship: the same protocol on all trials
        model = models[-1]
        model.info["protocol"] = ("labels: best stored classical detector per trial; shoe_threshold: SHOE grid "
                                  "value with the smallest mean 2-D error over the training trials")
        model.save(args.save_model)
        print(f"model written to {args.save_model}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
