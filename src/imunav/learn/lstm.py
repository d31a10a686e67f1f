"""LSTM zero-velocity classifier (Şahin 2022 §3.2 / §4.2; Wagstaff & Kelly, IPIN 2018).

Architecture (thesis): raw 6-channel IMU windows of 100 samples →
``layers`` stacked LSTM layers of ``hidden`` units (thesis 6 × 80,
:meth:`LstmConfig.thesis`; default 2 × 48 for the CPU budget) → a fully connected layer
to 2 logits → softmax; the foot is declared stationary when
``P(stationary) > 0.85``.  Cell (Hochreiter & Schmidhuber 1997 with the forget gate of Gers et al.
2000, as in PyTorch's ``torch.nn.LSTM``; the thesis's misprint corrected)::

    i = σ(W_ii x + b_ii + W_hi h + b_hi)     f = σ(W_if x + ... )
    g = tanh(W_ig x + ... )                  o = σ(W_io x + ... )
    c' = f ⊙ c + i ⊙ g                       h' = o ⊙ tanh(c')

Training (:func:`train_lstm`) uses PyTorch on the CPU (imported lazily; the
``learn`` extra) with cross-entropy, Adam and the thesis's augmentation
(random rotation of both triads, scale in [0.9, 1.1], Gaussian noise).  The
labels of each trial come from the best classical detector for that trial
(or any reference labels).  Weights and the input normalisation are saved to
a small ``.npz``; inference (:class:`LstmDetector`) is pure numpy, so running
the INS never needs torch.

Deviations from the thesis, chosen for a CPU budget and recorded in the
model file: besides the 6 raw channels the input carries ``log |ω|²`` and
``log (|f| - g)²`` (``features="raw"`` gives the thesis's raw input); the loss uses the labels of the last ``window - burn_in`` steps of
each window (the thesis uses only the last one, 100× fewer labels per unit of
compute); 3 epochs of 1000 windows per trial (the thesis: 7000 windows and
300 epochs, far beyond a CPU budget); a stance class weight of 6; random rotations of at most 10° (mounting
tolerance; ``max_rotation_deg=180`` gives the thesis's arbitrary rotation) and
gyro noise 0.01 rad/s (the thesis's σ = 0.075 on every channel is 4.3 °/s on
the gyros, larger than the stance signal); inference runs the network over windows of ``window`` samples
every ``window - burn_in`` samples and keeps the outputs that had at least
``burn_in`` samples of context, which matches the training exactly; a gait
prior (:meth:`LstmDetector.detect`, ``max_gap_s``) accepts P > 0.5 inside
stance-free stretches longer than 1.5 s.

Additions for recordings unlike the training set (issue 12): half of the
training windows are replayed 1-2x faster (:func:`time_warp`, ``speed``), so
that the short stances of a fast gait are seen; and the detector is checked
by SHOE (:func:`guard_stances`): a 10 s block where the LSTM marks fewer than
half of SHOE's stationary samples takes SHOE's flags, and the result says so.
The SHOE threshold is chosen on the training trials
(:func:`select_shoe_threshold`) and stored in the model.
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import (
    InvalidInputError,
    MissingDependencyError,
    ShapeError,
)
from imunav.ins.zupt.filter import ZuptFilter
from imunav.ins.zupt.lstm import (
    DEFAULT_MODEL_PATH,
    LstmConfig,
    LstmDetector,
    _derived,
    _features,
    guard_stances,
    input_features,
    lstm_forward,
)
from imunav.ins.zupt.metrics import error_2d
from imunav.ins.zupt.statistics import detector_statistic
from imunav.results import Result
from imunav.rotation import quat_conjugate, quat_rotate

__all__ = [
    "DEFAULT_MODEL_PATH",
    "SHOE_GUARD_GRID",
    "LstmConfig",
    "LstmDetector",
    "TrainingReport",
    "augment",
    "best_labels",
    "gravity_in_body",
    "guard_stances",
    "input_features",
    "lstm_forward",
    "random_rotations",
    "require_torch",
    "select_shoe_threshold",
    "time_warp",
    "train_lstm",
]

Array = NDArray[np.float64]

def random_rotations(n: int, max_angle: float, rng: np.random.Generator) -> Array:
    """``n`` rotation matrices with uniform random axes and angles uniform in [0, max_angle] rad
    (``max_angle = pi`` gives the whole of SO(3), not uniformly).

    Rodrigues' formula ``R = I + sin θ [k×] + (1 − cos θ) [k×]²``.

    Parameters
    ----------
    n : int
        Number of matrices.
    max_angle : float
        Largest rotation angle, rad.
    rng : numpy.random.Generator
        Random generator.

    Returns
    -------
    numpy.ndarray, shape (n, 3, 3)
        Rotation matrices.
    """
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    ang = rng.uniform(0.0, max_angle, n)
    K = np.zeros((n, 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = axis[:, 2], -axis[:, 1], axis[:, 0]
    s = np.sin(ang)[:, None, None]
    c = (1 - np.cos(ang))[:, None, None]
    return np.eye(3) + s * K + c * (K @ K)


def augment(x: Array, cfg: LstmConfig, rng: np.random.Generator) -> Array:
    """Thesis augmentation of raw windows (B, T, 6): rotation, scaling, Gaussian noise.

    Each window gets one random rotation (applied to both triads, at most ``cfg.max_rotation_deg``),
    one scale factor in ``cfg.scale`` and white noise of ``cfg.accel_noise_std`` (m/s²) / ``cfg.gyro_noise_std``
    (rad/s).

    Parameters
    ----------
    x : numpy.ndarray, shape (B, T, 6)
        Raw windows, accel (m/s²) then gyro (rad/s).
    cfg : LstmConfig
        Augmentation settings.
    rng : numpy.random.Generator
        Random generator.

    Returns
    -------
    numpy.ndarray, shape (B, T, 6)
        Augmented windows (a new array).
    """
    B = x.shape[0]
    R = random_rotations(B, np.radians(cfg.max_rotation_deg), rng)
    out = np.empty_like(x)
    out[..., :3] = np.einsum("bij,btj->bti", R, x[..., :3])
    out[..., 3:] = np.einsum("bij,btj->bti", R, x[..., 3:])
    out *= rng.uniform(cfg.scale[0], cfg.scale[1], (B, 1, 1))
    out[..., :3] += rng.normal(0.0, cfg.accel_noise_std, out[..., :3].shape)
    out[..., 3:] += rng.normal(0.0, cfg.gyro_noise_std, out[..., 3:].shape)
    return out


def time_warp(x: Array, gravity_body: Array, factor: float, start: float = 0.0,
              length: int | None = None) -> tuple[Array, Array]:
    """Play raw IMU samples ``factor`` times faster at the same sample rate.

    If the foot's motion ``p(t)``, ``R(t)`` is replayed as ``p(s t)``, ``R(s t)``,
    the angular rate scales by ``s`` and the kinematic acceleration by ``s²``,
    while gravity stays: ``ω' = s ω`` and ``f' = s² (f − f_g) + f_g`` with
    ``f_g = −Rᵀ g`` the accelerometer reading at rest (``gravity_body``).
    Samples are taken at ``u = start + s k`` by linear interpolation.

    Parameters
    ----------
    x : numpy.ndarray, shape (N, 6)
        Accel (m/s²) then gyro (rad/s), body FRD.
    gravity_body : numpy.ndarray, shape (N, 3)
        ``f_g`` of each sample, m/s² (e.g. from the ZUPT INS attitude, :func:`gravity_in_body`).
    factor : float
        Speed-up ``s`` > 0 (2 = twice as fast: a 0.6 s stance lasts 0.3 s).
    start : float, optional
        First (fractional) source sample, >= 0.
    length : int, optional
        Number of samples out (default: as many as fit).

    Returns
    -------
    warped : numpy.ndarray, shape (L, 6)
        The warped samples.
    u : numpy.ndarray, shape (L,)
        Their (fractional) source positions (to resample labels or a reference track).

    Raises
    ------
    ShapeError
        If ``x`` is not (N, 6) or ``gravity_body`` not (N, 3).
    InvalidInputError
        If ``factor`` is not finite and > 0, or the samples asked for do not fit.
    """
    xa = np.asarray(x, dtype=float)
    fg = np.asarray(gravity_body, dtype=float)
    if xa.ndim != 2 or xa.shape[1] != 6 or fg.shape != (xa.shape[0], 3):
        raise ShapeError(f"x must be (N, 6) and gravity_body (N, 3); got {xa.shape} and {fg.shape}")
    s = float(factor)
    if not (s > 0 and np.isfinite(s)):
        raise InvalidInputError(f"factor must be a finite speed-up > 0; got {factor}")
    n = xa.shape[0]
    fit = int(np.floor((n - 1 - start) / s)) + 1
    L = fit if length is None else int(length)
    if start < 0 or L < 1 or L > fit:
        raise InvalidInputError(f"{L} samples from {start} at factor {s} do not fit in {n} samples")
    u = start + s * np.arange(L)
    i0 = np.minimum(np.floor(u).astype(np.int64), n - 2) if n > 1 else np.zeros(L, np.int64)
    fr = (u - i0)[:, None] if n > 1 else np.zeros((L, 1))
    i1 = np.minimum(i0 + 1, n - 1)
    xi = xa[i0] * (1 - fr) + xa[i1] * fr
    gi = fg[i0] * (1 - fr) + fg[i1] * fr
    out = np.empty_like(xi)
    out[:, :3] = s * s * (xi[:, :3] - gi) + gi
    out[:, 3:] = s * xi[:, 3:]
    return out, u


def gravity_in_body(data: Any, stance: Any, g: float = 9.80665) -> Array:
    """Accelerometer reading at rest ``f_g = −Rᵀ (0, 0, g)`` per sample (N, 3), ``R`` from the ZUPT INS
    (:meth:`imunav.ins.ZuptFilter.run`) run with the stance flags ``stance``.

    Parameters
    ----------
    data : ImuData
        IMU recording (SI, body FRD).
    stance : array_like of bool, shape (N,)
        Stance flags for the ZUPT INS.
    g : float, optional
        Gravity magnitude, m/s².

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        ``f_g`` in the body frame, m/s² (``(0, 0, −g)`` for a level sensor).
    """

    q = ZuptFilter().run(data, np.asarray(stance, dtype=bool)).q_nb
    return quat_rotate(quat_conjugate(q), np.broadcast_to(np.array([0.0, 0.0, -g]), (q.shape[0], 3)))


@dataclass(frozen=True)
class TrainingReport(Result):
    """What :func:`train_lstm` did: loss per batch, accuracy on the training windows, time.

    Attributes
    ----------
    losses : numpy.ndarray, shape (batches,)
        Weighted cross-entropy of each batch.
    n_windows : int
        Number of training windows used.
    seconds : float
        Training time, s.
    train_accuracy : float
        Share of the trained steps classified correctly (at ``config.threshold``), in [0, 1].
    stopped_by_budget : bool
        True when ``config.time_budget_s`` stopped the training.
    extra : dict
        Further entries merged into :meth:`to_dict`.
    """

    losses: Array
    n_windows: int
    seconds: float
    train_accuracy: float
    stopped_by_budget: bool
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The report as plain JSON types, ``extra`` merged in.

        Returns
        -------
        dict
            Keys ``losses``, ``n_windows``, ``seconds``, ``train_accuracy``, ``stopped_by_budget`` and those
            of ``extra``.
        """
        return {"losses": self.losses.tolist(), "n_windows": self.n_windows, "seconds": self.seconds,
                "train_accuracy": self.train_accuracy, "stopped_by_budget": self.stopped_by_budget, **self.extra}


def require_torch() -> Any:
    """The ``torch`` module, or :class:`~imunav.errors.MissingDependencyError` naming ``imunav[learn]``.

    Only training needs torch (the ``learn`` extra, kept out of the core install: it is several hundred MB);
    inference is numpy.  Call it before slow preparations so that a missing torch is reported at once.

    Returns
    -------
    module
        ``torch``.

    Raises
    ------
    MissingDependencyError
        If torch is not installed.
    """
    try:
        import torch  # optional: the `learn` extra
    except ImportError as exc:
        raise MissingDependencyError("torch", "learn", "Training the LSTM zero-velocity detector") from exc
    return torch


#: torch's messages of an allocation it could not make (CPU: DefaultCPUAllocator "not enough memory"; CUDA: "out of
#: memory"), for torch versions whose OutOfMemoryError is a plain RuntimeError
_TORCH_OOM = re.compile(r"out of memory|not enough memory|DefaultCPUAllocator|[Uu]nable to allocate")


@contextlib.contextmanager
def _torch_memory(torch: Any, cfg: LstmConfig) -> Iterator[None]:
    """Turn torch running out of memory (``torch.OutOfMemoryError``, a ``RuntimeError`` saying so, a
    ``MemoryError``) into a :class:`MemoryError` that says what the training held and what to reduce."""
    ooms = tuple(t for t in (getattr(torch, "OutOfMemoryError", None),
                             getattr(getattr(torch, "cuda", None), "OutOfMemoryError", None)) if isinstance(t, type))
    try:
        yield
    except (MemoryError, RuntimeError) as exc:
        if not (isinstance(exc, MemoryError) or (ooms and isinstance(exc, ooms)) or _TORCH_OOM.search(str(exc))):
            raise
        said = " ".join(str(exc).split())
        said = (said[:160] + " ...") if len(said) > 160 else said or type(exc).__name__
        raise MemoryError(
            f"training the LSTM ran out of memory ({said}) with batches of {cfg.batch_size} windows of {cfg.window} "
            f"samples through {cfg.layers} x {cfg.hidden} LSTM units: the weights, their gradients and a batch's "
            f"activations grow with layers x hidden; reduce the model (LstmConfig.hidden / layers; command line: "
            f"--hidden / --layers) or the batch (LstmConfig.batch_size / window), or free memory") from exc


def train_lstm(trials: Sequence[Any], labels: Sequence[Any], config: LstmConfig | None = None, *,
               progress: Callable[[int, int, float], None] | None = None,
               threads: int | None = 1) -> tuple[LstmDetector, TrainingReport]:
    """Train the LSTM zero-velocity classifier on labelled recordings.

    Parameters
    ----------
    trials : sequence of ImuData
        Recordings (the same sensor rate as at inference), each at least ``config.window`` samples.
    labels : sequence of array_like of bool
        (N,) stance labels per trial (e.g. the best classical
        detector's output at its optimal threshold, see
        :func:`imunav.learn.best_labels`).
    config : LstmConfig, optional
        Architecture and training settings (default :class:`LstmConfig`).
    progress : callable, optional
        Called as ``progress(done_batches, total_batches, loss)``.
    threads : int or None, optional
        Torch CPU threads (default 1: the machine is shared; None leaves torch's default).

    Returns
    -------
    detector : LstmDetector
        The trained model (numpy inference).
    report : TrainingReport
        Losses, accuracy and time.

    Raises
    ------
    MissingDependencyError
        If torch is not installed (through :func:`require_torch`).
    InvalidInputError
        If there are no trials, not one label array per trial, or a trial is shorter than the window.
    ShapeError
        If a label array does not have one flag per sample.
    MemoryError
        If torch runs out of memory (``torch.OutOfMemoryError`` or its ``RuntimeError``), saying what to reduce.
    """
    cfg = LstmConfig() if config is None else config
    torch = require_torch()
    if len(trials) == 0 or len(trials) != len(labels):
        raise InvalidInputError(f"need as many label arrays as trials (>= 1); got {len(trials)} and {len(labels)}")
    X = [_features(d) for d in trials]
    nin = 6 if cfg.features == "raw" else 8
    Y = []
    for i, (x, y) in enumerate(zip(X, labels)):
        yy = np.asarray(y).astype(bool).ravel()
        if yy.shape[0] != x.shape[0]:
            raise ShapeError(f"labels of trial {i} have {yy.shape[0]} samples, the recording {x.shape[0]}")
        if x.shape[0] < cfg.window:
            raise InvalidInputError(f"trial {i} has {x.shape[0]} samples, fewer than the window {cfg.window}")
        Y.append(yy)
    warp = cfg.warp_fraction > 0 and cfg.speed != (1.0, 1.0)
    G = [gravity_in_body(d, y) for d, y in zip(trials, Y)] if warp else []
    allx = _derived(np.concatenate(X), cfg.features)
    mean = allx.mean(axis=0)
    std = allx.std(axis=0) + 1e-9
    rng = np.random.default_rng(cfg.seed)
    torch.manual_seed(cfg.seed)
    if threads:
        torch.set_num_threads(int(threads))
    with _torch_memory(torch, cfg):
        net = torch.nn.LSTM(nin, cfg.hidden, cfg.layers, batch_first=True)
        fc = torch.nn.Linear(cfg.hidden, 2)
        params = list(net.parameters()) + list(fc.parameters())
        opt = torch.optim.Adam(params, lr=cfg.lr)
        per_epoch = cfg.windows_per_trial * len(X)
        total_batches = cfg.epochs * int(np.ceil(per_epoch / cfg.batch_size))
        sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=cfg.lr, total_steps=max(total_batches, 2))
        # class weights (moving, stationary): > 1 favours recall of the stance, whose misses are
        # the costly error of a ZUPT INS (unbounded drift)
        cw = torch.tensor([1.0, float(cfg.stance_weight)])
        t0 = time.perf_counter()
        losses = []
        done = 0
        stopped = False
        lens = np.array([x.shape[0] for x in X])
        correct = 0
        counted = 0
        for _ in range(cfg.epochs):
            trial_idx = np.repeat(np.arange(len(X)), cfg.windows_per_trial)
            rng.shuffle(trial_idx)
            for b0 in range(0, trial_idx.size, cfg.batch_size):
                ti = trial_idx[b0:b0 + cfg.batch_size]
                if warp:
                    sp = np.where(rng.random(ti.size) < cfg.warp_fraction,
                                  rng.uniform(cfg.speed[0], cfg.speed[1], ti.size), 1.0)
                    # a warped window needs (window - 1) * speed + 1 source samples
                    sp = np.minimum(sp, (lens[ti] - 1) / (cfg.window - 1))
                    span = (cfg.window - 1) * sp
                    starts = rng.uniform(0.0, 1.0, ti.size) * (lens[ti] - 1 - span)
                    xb = np.empty((ti.size, cfg.window, 6))
                    yb = np.empty((ti.size, cfg.window), bool)
                    for k, (i, s0, f) in enumerate(zip(ti, starts, sp)):
                        xb[k], u = time_warp(X[i], G[i], f, s0, cfg.window)
                        yb[k] = Y[i][np.minimum(np.rint(u).astype(np.int64), lens[i] - 1)]
                else:
                    starts = rng.integers(0, lens[ti] - cfg.window + 1)
                    xb = np.stack([X[i][s:s + cfg.window] for i, s in zip(ti, starts)])
                    yb = np.stack([Y[i][s:s + cfg.window] for i, s in zip(ti, starts)])
                xb = (_derived(augment(xb, cfg, rng), cfg.features) - mean) / std
                xt = torch.as_tensor(xb, dtype=torch.float32)
                yt = torch.as_tensor(yb[:, cfg.burn_in:].astype(np.int64))
                out, _ = net(xt)
                logits = fc(out[:, cfg.burn_in:])
                loss = torch.nn.functional.cross_entropy(logits.reshape(-1, 2), yt.reshape(-1), weight=cw)
                opt.zero_grad()
                loss.backward()
                torch.nn.utils.clip_grad_norm_(params, 1.0)
                opt.step()
                sched.step()
                done += 1
                losses.append(loss.item())
                with torch.no_grad():
                    pred = torch.softmax(logits, -1)[..., 1] > cfg.threshold
                    correct += int((pred == yt.bool()).sum())
                    counted += int(yt.numel())
                if progress is not None:
                    progress(done, total_batches, losses[-1])
                if cfg.time_budget_s is not None and time.perf_counter() - t0 > cfg.time_budget_s:
                    stopped = True
                    break
            if stopped:
                break
    sd = net.state_dict()
    weights = []
    for l in range(cfg.layers):
        weights.append((sd[f"weight_ih_l{l}"].double().numpy().copy(), sd[f"weight_hh_l{l}"].double().numpy().copy(),
                        (sd[f"bias_ih_l{l}"] + sd[f"bias_hh_l{l}"]).double().numpy().copy()))
    det = LstmDetector(weights, fc.weight.detach().double().numpy().copy(), fc.bias.detach().double().numpy().copy(),
                       mean, std, cfg, {"n_trials": len(X), "batches": done, "seconds": time.perf_counter() - t0})
    rep = TrainingReport(np.array(losses), done * cfg.batch_size, time.perf_counter() - t0,
                         correct / max(counted, 1), stopped)
    return det, rep


#: SHOE thresholds searched for the guard's reference (:func:`select_shoe_threshold`).
SHOE_GUARD_GRID: Array = np.geomspace(1e6, 1e9, 31)


def select_shoe_threshold(trials: Sequence[Any], grid: Any = None, config: Any = None) -> tuple[float, Array]:
    """The single SHOE threshold with the smallest mean 2-D error over ``trials`` (the training trials).

    Each trial (a :class:`imunav.io.foot.FootTrial` with a reference
    ``position``) runs through the ZUPT INS (``config``) with SHOE at every
    ``grid`` value (default :data:`SHOE_GUARD_GRID`) and is scored with
    :func:`imunav.ins.error_2d`.

    Parameters
    ----------
    trials : sequence of FootTrial
        Training trials with a reference ``position``.
    grid : array_like, optional
        SHOE thresholds to try, > 0; default :data:`SHOE_GUARD_GRID`.
    config : ZuptConfig, optional
        Settings of the ZUPT INS.

    Returns
    -------
    threshold : float
        The grid value with the smallest mean error.
    errors : numpy.ndarray, shape (K,)
        Mean 2-D error per grid value, m.

    Raises
    ------
    InvalidInputError
        If the grid is empty or not positive, there are no trials, or a trial has no reference position.
    """

    g = SHOE_GUARD_GRID if grid is None else np.asarray(grid, dtype=float)
    if g.ndim != 1 or g.size == 0 or not np.all(g > 0):
        raise InvalidInputError("grid must be a non-empty 1-D sequence of SHOE thresholds > 0")
    if len(trials) == 0:
        raise InvalidInputError("need at least one trial to choose a SHOE threshold")
    E = np.zeros(g.size)
    for tr in trials:
        if tr.position is None:
            raise InvalidInputError(f"trial {tr.name!r} has no reference position to score SHOE thresholds")
        T = detector_statistic(tr.imu, "shoe")
        E += [error_2d(ZuptFilter(config).run(tr.imu, T < x).position, tr.position) for x in g]
    E /= len(trials)
    return float(g[int(np.argmin(E))]), E


def best_labels(trial: Any, detectors: Sequence[str] = ("shoe", "ared", "amvd", "mbgtd"),
                config: Any = None) -> tuple[NDArray[np.bool_], str, float]:
    """Stored labels of the classical detector that gives the smallest 2-D error on a trial.

    ``trial`` is a :class:`imunav.io.foot.FootTrial` with stored labels
    (``labels[name]``) and a reference ``position``; each label set runs
    through the ZUPT INS and is scored with :func:`imunav.ins.error_2d`.

    Parameters
    ----------
    trial : FootTrial
        Trial with stored labels and a reference position.
    detectors : sequence of str, optional
        Label sets to rank (those missing from the trial are skipped).
    config : ZuptConfig, optional
        Settings of the ZUPT INS.

    Returns
    -------
    labels : numpy.ndarray of bool, shape (N,)
        The best label set.
    detector : str
        Its detector name.
    error : float
        Its 2-D error, m.

    Raises
    ------
    InvalidInputError
        If the trial has no reference position or none of the label sets.
    """

    if trial.position is None:
        raise InvalidInputError(f"trial {trial.name!r} has no reference position to rank the detectors")
    best: tuple[float, str, Any] = (np.inf, "", None)
    for name in detectors:
        if name not in trial.labels:
            continue
        e = error_2d(ZuptFilter(config).run(trial.imu, trial.labels[name]).position, trial.position)
        if e < best[0]:
            best = (e, name, trial.labels[name])
    if best[2] is None:
        raise InvalidInputError(f"trial {trial.name!r} has none of the labels {list(detectors)}")
    return np.asarray(best[2], bool), best[1], float(best[0])
