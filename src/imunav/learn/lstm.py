"""LSTM zero-velocity classifier (Şahin 2022 §3.2 / §4.2; Wagstaff & Kelly 2018).

Architecture (thesis): raw 6-channel IMU windows of 100 samples →
``layers`` stacked LSTM layers of ``hidden`` units (thesis 6 × 80,
:meth:`LstmConfig.thesis`; default 2 × 48 for the CPU budget) → a fully connected layer
to 2 logits → softmax; the foot is declared stationary when
``P(stationary) > 0.85``.  Cell (spec §8.1, the thesis's misprint corrected)::

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

import json
import time
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import (
    ConfigError,
    FileFormatError,
    InvalidInputError,
    MissingDependencyError,
    ShapeError,
)
from imunav.ins.metrics import error_2d
from imunav.ins.result import DetectorResult
from imunav.ins.statistics import detector_statistic
from imunav.ins.zupt import run_zupt
from imunav.io._atomic import atomic_path
from imunav.learn import _kernels as _lk
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

#: The model trained on the shared pyshoe VICON trials (see README, section ins).
DEFAULT_MODEL_PATH = Path(__file__).resolve().parents[1] / "data" / "zupt_lstm.npz"


@dataclass(frozen=True)
class LstmConfig:
    """Architecture and training settings.

    Defaults: the thesis's windows (100 samples), stacked LSTM, softmax, 0.85
    threshold and augmentation, with a 2 × 48 network and 3 epochs of 1000
    windows per trial so that training fits a shared CPU (the thesis's 6 × 80
    network: :meth:`thesis`).  ``stance_weight`` weights the stationary class
    in the cross-entropy: a missed stance (unbounded drift) costs far more
    than a false one, and the 0.85 rule already suppresses false stances.  ``time_budget_s`` optionally stops training
    early (then the result depends on the machine speed).
    """

    layers: int = 2
    hidden: int = 48
    window: int = 100
    burn_in: int = 50
    threshold: float = 0.85
    windows_per_trial: int = 1000
    epochs: int = 3
    batch_size: int = 64
    lr: float = 3e-3
    max_rotation_deg: float = 10.0
    scale: tuple[float, float] = (0.9, 1.1)
    noise_acc: float = 0.075
    noise_gyro: float = 0.01
    time_budget_s: float | None = None
    seed: int = 0
    features: str = "raw+log"
    stance_weight: float = 6.0
    max_gap_s: float | None = 1.5
    fallback_threshold: float = 0.5
    speed: tuple[float, float] = (1.0, 2.0)
    warp_fraction: float = 0.5
    guard: bool = True
    shoe_threshold: float = 1.0e8
    guard_fill_s: float | None = None
    guard_bridge_s: float | None = None
    guard_min_ratio: float = 0.5
    guard_max_count_ratio: float | None = None
    guard_block_s: float = 10.0

    def __post_init__(self) -> None:
        if self.layers < 1 or self.hidden < 1:
            raise ConfigError(f"layers and hidden must be >= 1; got {self.layers}, {self.hidden}")
        if not 0 <= self.burn_in < self.window:
            raise ConfigError(f"burn_in must be in [0, window); got {self.burn_in} with window {self.window}")
        if not 0.0 < self.threshold < 1.0:
            raise ConfigError(f"threshold must be in (0, 1); got {self.threshold}")
        if self.scale[0] <= 0 or self.scale[1] < self.scale[0]:
            raise ConfigError(f"scale must be (low, high) with 0 < low <= high; got {self.scale}")
        if self.max_gap_s is not None and not self.max_gap_s > 0:
            raise ConfigError(f"max_gap_s must be > 0 s or None; got {self.max_gap_s}")
        if not 0.0 < self.fallback_threshold < 1.0:
            raise ConfigError(f"fallback_threshold must be in (0, 1); got {self.fallback_threshold}")
        if self.features not in ("raw", "raw+log"):
            raise ConfigError(f"features must be 'raw' (thesis) or 'raw+log'; got {self.features!r}")
        if self.batch_size < 1 or self.epochs < 1 or self.windows_per_trial < 1:
            raise ConfigError("batch_size, epochs and windows_per_trial must be >= 1")
        if not 0 < self.speed[0] <= self.speed[1]:
            raise ConfigError(f"speed must be (low, high) time-warp factors with 0 < low <= high; got {self.speed}")
        if not 0.0 <= self.warp_fraction <= 1.0:
            raise ConfigError(f"warp_fraction must be in [0, 1]; got {self.warp_fraction}")
        if not (self.shoe_threshold > 0 and np.isfinite(self.shoe_threshold)):
            raise ConfigError(f"shoe_threshold must be a finite SHOE threshold > 0; got {self.shoe_threshold}")
        if not 0.0 <= self.guard_min_ratio <= 1.0 or not (self.guard_max_count_ratio is None
                                                           or self.guard_max_count_ratio >= 1.0):
            raise ConfigError("guard_min_ratio must be in [0, 1] and guard_max_count_ratio >= 1 or None; got "
                              f"{self.guard_min_ratio}, {self.guard_max_count_ratio}")
        for name in ("guard_fill_s", "guard_bridge_s"):
            v = getattr(self, name)
            if v is not None and not v >= 0:
                raise ConfigError(f"{name} must be >= 0 s or None (off); got {v}")
        if not self.guard_block_s > 0:
            raise ConfigError(f"guard_block_s must be > 0 s; got {self.guard_block_s}")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def thesis(cls, **changes: Any) -> LstmConfig:
        """The thesis's 6 × 80 network (Şahin 2022 §4.2), other defaults unchanged."""
        return cls(**{"layers": 6, "hidden": 80, **changes})


def _sigmoid(x: Array) -> Array:
    return 0.5 * (1.0 + np.tanh(0.5 * x))


def lstm_forward(weights: Sequence[tuple[Array, Array, Array]], fc_w: Array, fc_b: Array, x: Array) -> Array:
    """Stacked LSTM + linear head in numpy; returns P(stationary) (B, T).

    ``weights[l] = (W_ih (4H, in), W_hh (4H, H), b (4H,))`` with the gate
    order i, f, g, o (PyTorch's); zero initial states.
    """
    h_seq = np.asarray(x, dtype=np.float64)
    if h_seq.ndim != 3:
        raise ShapeError(f"x must be (batch, time, channels); got {h_seq.shape}")
    B, T, _ = h_seq.shape
    for W_ih, W_hh, b in weights:
        H = W_hh.shape[1]
        xin = h_seq @ W_ih.T + b  # (B, T, 4H)
        h = np.zeros((B, H))
        c = np.zeros((B, H))
        out = np.empty((B, T, H))
        W_hhT = np.ascontiguousarray(W_hh.T)
        for t in range(T):
            z = xin[:, t] + h @ W_hhT
            i = _sigmoid(z[:, :H])
            f = _sigmoid(z[:, H:2 * H])
            g = np.tanh(z[:, 2 * H:3 * H])
            o = _sigmoid(z[:, 3 * H:])
            c = f * c + i * g
            h = o * np.tanh(c)
            out[:, t] = h
        h_seq = out
    logits = h_seq @ fc_w.T + fc_b  # (B, T, 2)
    d = logits[..., 1] - logits[..., 0]
    return _sigmoid(d)  # softmax of 2 classes


class LstmDetector:
    """Numpy inference of a trained LSTM zero-velocity classifier."""

    def __init__(self, weights: list[tuple[Array, Array, Array]], fc_w: Array, fc_b: Array, mean: Array,
                 std: Array, config: LstmConfig, info: dict[str, Any] | None = None) -> None:
        self.weights = weights
        self.fc_w = fc_w
        self.fc_b = fc_b
        self.mean = mean
        self.std = std
        self.config = config
        self.info = dict(info or {})

    # -- persistence ---------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write weights (float32), normalisation and settings to ``.npz`` atomically."""
        p = Path(path)
        arrays: dict[str, Any] = {"fc_w": self.fc_w.astype(np.float32), "fc_b": self.fc_b.astype(np.float32),
                                  "mean": self.mean, "std": self.std}
        for l, (a, b, c) in enumerate(self.weights):
            arrays[f"w_ih_{l}"] = a.astype(np.float32)
            arrays[f"w_hh_{l}"] = b.astype(np.float32)
            arrays[f"b_{l}"] = c.astype(np.float32)
        arrays["meta"] = np.array(json.dumps({"config": self.config.to_dict(), "info": self.info}))

        with atomic_path(p) as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)
        return p

    @classmethod
    def load(cls, path: str | Path | None = None) -> LstmDetector:
        """Load a model file (default: the shipped model)."""
        p = DEFAULT_MODEL_PATH if path is None else Path(path)
        if not p.is_file():
            raise FileFormatError(f"LSTM model file not found: {p}; train one with `imunav zupt train DIR`")
        try:
            with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                cfgd = meta["config"]
                for key in ("scale", "speed"):
                    if key in cfgd:
                        cfgd[key] = tuple(cfgd[key])
                # a model saved before the SHOE guard existed has no guard threshold chosen on its own
                # training trials: keep its behaviour (no guard) rather than borrow the shipped model's
                cfgd.setdefault("guard", False)
                cfg = LstmConfig(**cfgd)
                weights = [(z[f"w_ih_{l}"].astype(float), z[f"w_hh_{l}"].astype(float), z[f"b_{l}"].astype(float))
                           for l in range(cfg.layers)]
                return cls(weights, z["fc_w"].astype(float), z["fc_b"].astype(float), z["mean"].astype(float),
                           z["std"].astype(float), cfg, meta.get("info"))
        except (KeyError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as exc:
            raise FileFormatError(f"{p}: not an imunav LSTM model file, or a truncated one "
                                  f"({type(exc).__name__}: {exc}); train one with `imunav zupt train DIR`") from exc

    # -- inference -----------------------------------------------------------
    def probability(self, data: Any) -> Array:
        """P(stationary) per sample (N,), each from a window with >= ``burn_in`` samples of context
        (the first window's outputs excepted)."""
        x = _derived(_features(data), self.config.features)
        x = (x - self.mean) / self.std
        n = x.shape[0]
        W = self.config.window
        burn = self.config.burn_in
        hop = W - burn
        if n <= W:
            return lstm_forward(self.weights, self.fc_w, self.fc_b, x[None])[0]
        starts = list(range(0, n - W + 1, hop))
        if starts[-1] != n - W:
            starts.append(n - W)
        batch = np.stack([x[s:s + W] for s in starts])
        out = np.empty(n)
        probs = np.empty((len(starts), W))
        for b0 in range(0, len(starts), 512):
            probs[b0:b0 + 512] = lstm_forward(self.weights, self.fc_w, self.fc_b, batch[b0:b0 + 512])
        out[:W] = probs[0]
        for j, s in enumerate(starts[1:], start=1):
            out[s + burn:s + W] = probs[j, burn:]
        return out

    def detect(self, data: Any, threshold: float | None = None, *, max_gap_s: Any = "config",
               fallback_threshold: float | None = None, guard: bool | None = None,
               probability: Any = None) -> Any:
        """Zero-velocity flags as a :class:`~imunav.ins.DetectorResult`: the LSTM, checked by SHOE.

        1. LSTM: ``P(stationary) > threshold`` (0.85).
        2. Gait prior ``max_gap_s`` (default from the config: 1.5 s; None turns
           it off): inside any run longer than this without a stance, samples
           with ``P > fallback_threshold`` (0.5) are declared stationary too.
        3. Stance guard (``guard``, default from the config: on), against SHOE
           at ``config.shoe_threshold`` (:func:`guard_stances`): every
           ``guard_block_s`` (10 s) block in which the LSTM marks fewer than
           ``guard_min_ratio`` (0.5) times SHOE's stationary samples takes
           SHOE's flags (a missed stance makes a ZUPT INS drift without bound;
           an unseen fast gait is where the LSTM misses them).  The other checks
           of :func:`guard_stances` (``guard_fill_s``, ``guard_bridge_s``,
           ``guard_max_count_ratio``) are off by default: the leave-one-session-out
           selection in ``benchmarks/bench_zupt_lstm_cv.py`` did not keep them.

        ``params["guard"]`` reports what the guard did (``fallback_fraction``:
        share of samples that took SHOE's flags; ``fallback``: any block did).
        ``probability``: ``self.probability(data)`` if already computed (skips the network).
        """

        if isinstance(max_gap_s, str):
            max_gap_s = self.config.max_gap_s
        if fallback_threshold is None:
            fallback_threshold = self.config.fallback_threshold
        use_guard = self.config.guard if guard is None else bool(guard)
        thr = self.config.threshold if threshold is None else float(threshold)
        if not 0.0 < thr < 1.0:
            raise InvalidInputError(f"threshold must be a probability in (0, 1); got {thr}")
        if probability is None:
            p = self.probability(data)
        else:
            p = np.asarray(probability, dtype=float)
            if p.shape != (len(data.t),):
                raise ShapeError(f"probability must have one value per sample ({len(data.t)}); got {p.shape}")
        zv = p > thr
        fs = _rate(data)
        if max_gap_s is not None:
            zv = _fill_gaps(zv, p, round(max_gap_s * fs), fallback_threshold)
        params: dict[str, Any] = {"threshold": thr, "layers": self.config.layers, "hidden": self.config.hidden,
                                  "max_gap_s": max_gap_s}
        if use_guard:
            ref = detector_statistic(data, "shoe") < self.config.shoe_threshold
            c = self.config
            zv, info = guard_stances(zv, ref, fs, min_ratio=c.guard_min_ratio, max_count_ratio=c.guard_max_count_ratio,
                                     block_s=c.guard_block_s, min_stance_s=c.guard_fill_s,
                                     max_bridge_s=c.guard_bridge_s)
            params["guard"] = {"shoe_threshold": self.config.shoe_threshold, **info}
        return DetectorResult(zv, p, np.full(p.shape, thr), "lstm", params)


def _rate(data: Any) -> float:
    t = np.asarray(data.t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise InvalidInputError(f"data.t must be 1-D with >= 2 samples; got shape {t.shape}")
    dt = float(np.median(np.diff(t)))
    if not dt > 0:
        raise InvalidInputError(f"data.t must increase; median step {dt}")
    return 1.0 / dt


def guard_stances(zv: Any, reference: Any, fs: float, *, min_ratio: float = 0.5,
                  max_count_ratio: float | None = 1.5, block_s: float = 10.0, min_stance_s: float | None = 0.1,
                  max_bridge_s: float | None = 0.1) -> tuple[NDArray[np.bool_], dict[str, Any]]:
    """Check learned stance flags ``zv`` against a classical detector's ``reference`` flags.

    A walking foot stands still once per gait cycle, and a missed stance makes
    a ZUPT INS drift without bound while a split one costs little, so the
    checks only ever add stance or hand a block to the reference:

    1. every reference stance of at least ``min_stance_s`` (0.1 s: a foot's
       ground contact lasts longer even in a sprint) that holds no stationary
       sample of ``zv`` is added (a missed stance);
    2. every gap of at most ``max_bridge_s`` (0.1 s: shorter than any swing)
       between two stances of ``zv`` in which the reference is stationary
       throughout is closed (a split stance);
    3. the record is cut into blocks of ``block_s``; a block in which ``zv``
       (after 1-2) marks fewer than ``min_ratio`` times the reference's
       stationary samples, or starts more than ``max_count_ratio`` times as many
       stances (and at least 3), takes the reference flags (fallback).

    ``min_stance_s`` / ``max_bridge_s`` None turn checks 1 / 2 off;
    ``min_ratio`` 0 and ``max_count_ratio`` None turn off the two tests of 3.

    Returns ``(flags, info)`` with ``info``: ``filled_stances``,
    ``bridged_gaps``, ``fallback_blocks``, ``blocks``, ``fallback_fraction``
    (share of samples that took the reference) and ``fallback`` (bool).
    """

    z = np.ascontiguousarray(np.asarray(zv, dtype=bool))
    r = np.ascontiguousarray(np.asarray(reference, dtype=bool))
    if z.ndim != 1 or r.shape != z.shape:
        raise ShapeError(f"zv and reference must be 1-D flags of one length; got {z.shape} and {r.shape}")
    if not (fs > 0 and np.isfinite(fs)):
        raise InvalidInputError(f"fs must be a finite rate > 0 Hz; got {fs}")
    if (not 0.0 <= min_ratio <= 1.0 or not (max_count_ratio is None or max_count_ratio >= 1.0) or not block_s > 0
            or (min_stance_s is not None and min_stance_s < 0) or (max_bridge_s is not None and max_bridge_s < 0)):
        raise InvalidInputError("need 0 <= min_ratio <= 1, max_count_ratio >= 1 (or None), block_s > 0, "
                                "min_stance_s >= 0 and max_bridge_s >= 0 (or None); got "
                                f"{min_ratio}, {max_count_ratio}, {block_s}, {min_stance_s}, {max_bridge_s}")
    out, filled = z.copy(), 0
    if min_stance_s is not None:
        out, filled = _lk.fill_missed(out, r, max(1, round(min_stance_s * fs)))
    bridged = 0
    if max_bridge_s is not None:
        out, bridged = _lk.bridge_gaps(out, r, round(max_bridge_s * fs))
    block = max(1, round(block_s * fs))
    mcr = np.inf if max_count_ratio is None else float(max_count_ratio)
    bad = _lk.block_gate(out, r, block, float(min_ratio), mcr)
    n_fb = 0
    for b in np.flatnonzero(bad):
        a, e = b * block, min(z.size, (b + 1) * block)
        out[a:e] = r[a:e]
        n_fb += e - a
    info = {"filled_stances": int(filled), "bridged_gaps": int(bridged), "fallback_blocks": int(bad.sum()),
            "blocks": int(bad.size), "fallback_fraction": n_fb / max(z.size, 1), "fallback": bool(bad.any())}
    return out, info


def _fill_gaps(zv: NDArray[np.bool_], p: Array, max_gap: int, thr: float) -> NDArray[np.bool_]:
    out = zv.copy()
    d = np.diff(np.concatenate([[1], zv.astype(np.int8), [1]]))
    starts = np.flatnonzero(d == -1)
    stops = np.flatnonzero(d == 1)
    for a, b in zip(starts, stops):
        if b - a > max_gap:
            out[a:b] = p[a:b] > thr
    return out


def _features(data: Any) -> Array:
    try:
        a = np.asarray(data.accel, dtype=float)
        w = np.asarray(data.gyro, dtype=float)
    except AttributeError as exc:
        raise InvalidInputError(f"data must be an ImuData; got {type(data).__name__}") from exc
    if a.ndim != 2 or a.shape[1] != 3 or w.shape != a.shape:
        raise ShapeError(f"accel {a.shape} and gyro {w.shape} must both be (N, 3)")
    return np.concatenate([a, w], axis=1)


def input_features(data: Any, kind: str = "raw+log") -> Array:
    """Network input features (N, 6 or 8) of a recording (before normalisation)."""
    return _derived(_features(data), kind)


def _derived(x: Array, kind: str) -> Array:
    """Network input from raw (..., 6) samples: the raw channels, plus for
    ``"raw+log"`` the rotation-invariant ``log(|ω|² + 1e-4)`` and
    ``log((|f| - 9.81)² + 1e-3)`` (the quantities the classical detectors
    threshold, on the log scale where their thresholds live)."""
    if kind == "raw":
        return x
    w2 = np.sum(x[..., 3:6] ** 2, axis=-1, keepdims=True)
    fa = np.linalg.norm(x[..., 0:3], axis=-1, keepdims=True) - 9.81
    return np.concatenate([x, np.log(w2 + 1e-4), np.log(fa * fa + 1e-3)], axis=-1)


def random_rotations(n: int, max_angle: float, rng: np.random.Generator) -> Array:
    """``n`` rotation matrices with uniform random axes and angles uniform in [0, max_angle] rad
    (``max_angle = pi`` gives the whole of SO(3), not uniformly)."""
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
    """Thesis augmentation of raw windows (B, T, 6): rotation, scaling, Gaussian noise."""
    B = x.shape[0]
    R = random_rotations(B, np.radians(cfg.max_rotation_deg), rng)
    out = np.empty_like(x)
    out[..., :3] = np.einsum("bij,btj->bti", R, x[..., :3])
    out[..., 3:] = np.einsum("bij,btj->bti", R, x[..., 3:])
    out *= rng.uniform(cfg.scale[0], cfg.scale[1], (B, 1, 1))
    out[..., :3] += rng.normal(0.0, cfg.noise_acc, out[..., :3].shape)
    out[..., 3:] += rng.normal(0.0, cfg.noise_gyro, out[..., 3:].shape)
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
    x : (N, 6) accel (m/s²) then gyro (rad/s).
    gravity_body : (N, 3) ``f_g`` of each sample (e.g. from the ZUPT INS attitude).
    factor : ``s`` > 0 (2 = twice as fast: a 0.6 s stance lasts 0.3 s).
    start : first (fractional) sample; ``length``: samples out (default: as many as fit).

    Returns
    -------
    (warped (L, 6), u (L,)): the samples and the source positions (to resample labels
    or a reference track).
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
    (:func:`imunav.ins.run_zupt`) run with the stance flags ``stance``."""

    q = run_zupt(data, np.asarray(stance, dtype=bool)).quaternion
    return quat_rotate(quat_conjugate(q), np.broadcast_to(np.array([0.0, 0.0, -g]), (q.shape[0], 3)))


@dataclass(frozen=True)
class TrainingReport:
    """What :func:`train_lstm` did: loss per batch, accuracy on the training windows, time."""

    losses: Array
    n_windows: int
    seconds: float
    train_accuracy: float
    stopped_by_budget: bool
    extra: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
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
    """
    try:
        import torch  # optional: the `learn` extra
    except ImportError as exc:
        raise MissingDependencyError("torch", "learn", "Training the LSTM zero-velocity detector") from exc
    return torch


def train_lstm(trials: Sequence[Any], labels: Sequence[Any], config: LstmConfig | None = None, *,
               progress: Callable[[int, int, float], None] | None = None,
               threads: int | None = 1) -> tuple[LstmDetector, TrainingReport]:
    """Train the LSTM zero-velocity classifier on labelled recordings.

    Parameters
    ----------
    trials : ImuData recordings (the same sensor rate as at inference).
    labels : (N,) bool stance labels per trial (e.g. the best classical
        detector's output at its optimal threshold, see
        :func:`imunav.learn.best_labels`).
    config : :class:`LstmConfig`.
    progress : called as ``progress(done_batches, total_batches, loss)``.
    threads : torch CPU threads (default 1: the machine is shared).
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
    :func:`imunav.ins.error_2d`.  Returns ``(threshold, mean error per grid value)``.
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
        E += [error_2d(run_zupt(tr.imu, T < x, config).position, tr.position) for x in g]
    E /= len(trials)
    return float(g[int(np.argmin(E))]), E


def best_labels(trial: Any, detectors: Sequence[str] = ("shoe", "ared", "amvd", "mbgtd"),
                config: Any = None) -> tuple[NDArray[np.bool_], str, float]:
    """Stored labels of the classical detector that gives the smallest 2-D error on a trial.

    ``trial`` is a :class:`imunav.io.foot.FootTrial` with stored labels
    (``labels[name]``) and a reference ``position``; each label set runs
    through the ZUPT INS and is scored with :func:`imunav.ins.error_2d`.
    Returns ``(labels, detector, error)``.
    """

    if trial.position is None:
        raise InvalidInputError(f"trial {trial.name!r} has no reference position to rank the detectors")
    best: tuple[float, str, Any] = (np.inf, "", None)
    for name in detectors:
        if name not in trial.labels:
            continue
        e = error_2d(run_zupt(trial.imu, trial.labels[name], config).position, trial.position)
        if e < best[0]:
            best = (e, name, trial.labels[name])
    if best[2] is None:
        raise InvalidInputError(f"trial {trial.name!r} has none of the labels {list(detectors)}")
    return np.asarray(best[2], bool), best[1], float(best[0])
