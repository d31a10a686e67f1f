"""LSTM zero-velocity detector, inference (numpy only): :class:`LstmDetector` and its network.

The architecture, the input features, the windowing and the SHOE guard are
described in :mod:`imunav.learn.lstm`, which trains the network (PyTorch, the
``learn`` extra) and re-exports everything here.  Inference sits in ``ins``
beside the classical detectors, which dispatch to it
(``detect_zero_velocity(data, "lstm")``), so that ``ins`` never imports the
training code that imports ``ins``.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.errors import ConfigError, FileFormatError, InvalidInputError, ShapeError
from imunav.files import atomic_path
from imunav.ins.zupt import _lstm_kernels as _lk
from imunav.ins.zupt.result import DetectorResult
from imunav.ins.zupt.statistics import detector_statistic

__all__ = ["DEFAULT_MODEL_PATH", "LstmConfig", "LstmDetector", "guard_stances", "input_features", "lstm_forward"]

Array = NDArray[np.float64]

#: The model trained on the shared pyshoe VICON trials (see README, section ins).
DEFAULT_MODEL_PATH = Path(__file__).resolve().parents[2] / "data" / "zupt_lstm.npz"


# vocab_rename: off (the old spellings a saved model file holds)
#: LstmConfig fields renamed by issue 25 (one vocabulary), as a model file saved before may spell them
_RENAMED_FIELDS = {"noise_acc": "accel_noise_std", "noise_gyro": "gyro_noise_std"}
# vocab_rename: on


@dataclass(frozen=True)
class LstmConfig:
    """Architecture and training settings.

    Defaults: the thesis's windows (100 samples), stacked LSTM, softmax, 0.85
    threshold and augmentation, with a 2 × 48 network and 3 epochs of 1000
    windows per trial so that training fits a shared CPU (the thesis's 6 × 80
    network: :meth:`thesis`).  ``stance_weight`` weights the stationary class
    in the cross-entropy: a missed stance (unbounded drift) costs far more
    than a false one, and the 0.85 rule already suppresses false stances.  ``time_budget_s`` optionally stops training
    early (then the result depends on the machine speed).  Reference: F. Şahin, *Derin öğrenme yöntemleri ile
    ataletsel navigasyon sistemlerinde doğruluğun geliştirilmesi*, MSc thesis, Kırıkkale University, 2022, §4.2.

    Attributes
    ----------
    layers : int
        Number of stacked LSTM layers, >= 1.
    hidden : int
        Hidden units per layer, >= 1.
    window : int
        Window length, samples.
    burn_in : int
        Leading samples of each window whose outputs are not used (context), in [0, window).
    threshold : float
        Stance when ``P(stationary) > threshold``, in (0, 1).
    windows_per_trial : int
        Training windows drawn from each trial per epoch.
    epochs : int
        Training epochs.
    batch_size : int
        Windows per batch.
    lr : float
        Peak learning rate of Adam (one-cycle schedule).
    max_rotation_deg : float
        Largest random rotation of the augmentation, degrees.
    scale : tuple of float
        (low, high) range of the random scale factor of the augmentation.
    accel_noise_std : float
        Standard deviation of the accelerometer noise added in augmentation, m/s².
    gyro_noise_std : float
        Standard deviation of the gyro noise added in augmentation, rad/s.
    time_budget_s : float or None
        Stop training after this many seconds (None: no limit).
    seed : int
        Seed of the random generators.
    features : {"raw+log", "raw"}
        Network input: the 6 raw channels, plus for ``"raw+log"`` ``log |ω|²`` and ``log (|f| − g)²``.
    stance_weight : float
        Weight of the stationary class in the cross-entropy.
    max_gap_s : float or None
        Gait prior: inside stance-free runs longer than this, s, ``P > fallback_threshold`` is a
        stance (None: off).
    fallback_threshold : float
        Probability threshold of the gait prior, in (0, 1).
    speed : tuple of float
        (low, high) time-warp factors of the training windows.
    warp_fraction : float
        Share of training windows that are time-warped, in [0, 1].
    guard : bool
        Check the flags against SHOE (:func:`guard_stances`).
    shoe_threshold : float
        SHOE threshold of the guard's reference flags.
    guard_fill_s : float or None
        ``min_stance_s`` of :func:`guard_stances`, s (None: off).
    guard_bridge_s : float or None
        ``max_bridge_s`` of :func:`guard_stances`, s (None: off).
    guard_min_ratio : float
        ``min_ratio`` of :func:`guard_stances`, in [0, 1].
    guard_max_count_ratio : float or None
        ``max_count_ratio`` of :func:`guard_stances`, >= 1 (None: off).
    guard_block_s : float
        ``block_s`` of :func:`guard_stances`, s.

    Raises
    ------
    ConfigError
        If a value is out of range.
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
    accel_noise_std: float = 0.075
    gyro_noise_std: float = 0.01
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
        """The settings as a plain dict.

        Returns
        -------
        dict
            One key per field.
        """
        return asdict(self)

    @classmethod
    def large_network(cls, **changes: Any) -> LstmConfig:
        """The large 6 × 80 network of the source (Şahin 2022 §4.2), other defaults unchanged.

        Parameters
        ----------
        **changes
            Fields to set (they override the 6 × 80 too).

        Returns
        -------
        LstmConfig
            The settings.
        """
        return cls(**{"layers": 6, "hidden": 80, **changes})


def _sigmoid(x: Array) -> Array:
    return 0.5 * (1.0 + np.tanh(0.5 * x))


def lstm_forward(weights: Sequence[tuple[Array, Array, Array]], fc_w: Array, fc_b: Array, x: Array) -> Array:
    """Stacked LSTM + linear head in numpy; returns P(stationary) (B, T).

    ``weights[l] = (W_ih (4H, in), W_hh (4H, H), b (4H,))`` with the gate
    order i, f, g, o (PyTorch's); zero initial states.  The cell is that of Hochreiter &
    Schmidhuber (Neural Computation 9(8), 1997) with a forget gate (Gers, Schmidhuber & Cummins,
    Neural Computation 12(10), 2000)::

        i = σ(W_ii x + W_hi h + b_i)    f = σ(W_if x + W_hf h + b_f)
        g = tanh(W_ig x + W_hg h + b_g) o = σ(W_io x + W_ho h + b_o)
        c' = f ⊙ c + i ⊙ g              h' = o ⊙ tanh(c')

    and the two-class softmax of the head is ``σ(logit_1 − logit_0)``.

    Parameters
    ----------
    weights : sequence of tuple of numpy.ndarray
        One ``(W_ih, W_hh, b)`` per layer (the two PyTorch biases summed).
    fc_w : numpy.ndarray, shape (2, H)
        Weights of the linear head (classes moving, stationary).
    fc_b : numpy.ndarray, shape (2,)
        Bias of the linear head.
    x : numpy.ndarray, shape (B, T, C)
        Normalised input windows.

    Returns
    -------
    numpy.ndarray, shape (B, T)
        P(stationary) at every step.

    Raises
    ------
    ShapeError
        If ``x`` is not 3-D.
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
    """Numpy inference of a trained LSTM zero-velocity classifier.

    Parameters
    ----------
    weights : list of tuple of numpy.ndarray
        One ``(W_ih (4H, in), W_hh (4H, H), b (4H,))`` per layer (see :func:`lstm_forward`).
    fc_w : numpy.ndarray, shape (2, H)
        Weights of the linear head.
    fc_b : numpy.ndarray, shape (2,)
        Bias of the linear head.
    mean : numpy.ndarray, shape (C,)
        Mean of the input features (normalisation).
    std : numpy.ndarray, shape (C,)
        Standard deviation of the input features (normalisation).
    config : LstmConfig
        Architecture and detection settings.
    info : dict, optional
        Free-form training information saved with the model.
    """

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
        """Write weights (float32), normalisation and settings to ``.npz`` atomically.

        Parameters
        ----------
        path : str or pathlib.Path
            File to write.

        Returns
        -------
        pathlib.Path
            The path written.
        """
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
        """Load a model file (default: the shipped model).

        Parameters
        ----------
        path : str or pathlib.Path, optional
            Model file written by :meth:`save`; default :data:`DEFAULT_MODEL_PATH`.

        Returns
        -------
        LstmDetector
            The model.

        Raises
        ------
        FileFormatError
            If the file is missing, truncated or not an imunav LSTM model.
        """
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
                # a model saved before issue 25's renames names two fields the old way
                for old, new in _RENAMED_FIELDS.items():
                    if old in cfgd:
                        cfgd[new] = cfgd.pop(old)
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
        (the first window's outputs excepted).

        Parameters
        ----------
        data : ImuData
            IMU recording (``t`` s, ``accel`` m/s², ``gyro`` rad/s, body FRD), at the rate of the
            training data.

        Returns
        -------
        numpy.ndarray, shape (N,)
            Probability that the foot is stationary, in (0, 1).
        """
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

        Parameters
        ----------
        data : ImuData
            IMU recording (``t`` s, ``accel`` m/s², ``gyro`` rad/s, body FRD), at the rate of the
            training data.
        threshold : float, optional
            Probability threshold in (0, 1); default ``config.threshold``.
        max_gap_s : float or None, optional
            Gait prior, s (None: off); default ``config.max_gap_s``.
        fallback_threshold : float, optional
            Threshold of the gait prior; default ``config.fallback_threshold``.
        guard : bool, optional
            Apply the SHOE guard; default ``config.guard``.
        probability : array_like, shape (N,), optional
            ``self.probability(data)`` if already computed (skips the network).

        Returns
        -------
        DetectorResult
            Flags, the probability as ``statistic``, the threshold and ``params`` (with ``guard``).

        Raises
        ------
        InvalidInputError
            If ``threshold`` is not in (0, 1).
        ShapeError
            If ``probability`` does not have one value per sample.
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

    Parameters
    ----------
    zv : array_like of bool, shape (N,)
        Learned stance flags.
    reference : array_like of bool, shape (N,)
        Reference flags (e.g. SHOE).
    fs : float
        Sample rate, Hz, > 0.
    min_ratio : float, optional
        Check 3: least ratio of stationary samples (``zv`` / reference) per block, in [0, 1].
    max_count_ratio : float or None, optional
        Check 3: most ratio of stance counts per block, >= 1.
    block_s : float, optional
        Block length, s, > 0.
    min_stance_s : float or None, optional
        Check 1: shortest reference stance added, s.
    max_bridge_s : float or None, optional
        Check 2: longest gap closed, s.

    Returns
    -------
    flags : numpy.ndarray of bool, shape (N,)
        The checked flags.
    info : dict
        ``filled_stances``, ``bridged_gaps``, ``fallback_blocks``, ``blocks``, ``fallback_fraction``
        (share of samples that took the reference) and ``fallback`` (bool).

    Raises
    ------
    ShapeError
        If ``zv`` and ``reference`` are not 1-D of one length.
    InvalidInputError
        If ``fs`` or a setting is out of range.
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
    """Network input features (N, 6 or 8) of a recording (before normalisation).

    Parameters
    ----------
    data : ImuData
        IMU recording (``accel`` m/s², ``gyro`` rad/s, body FRD).
    kind : {"raw+log", "raw"}, optional
        ``"raw"``: accel then gyro; ``"raw+log"`` adds ``log(|ω|² + 1e-4)`` and
        ``log((|f| − 9.81)² + 1e-3)``.

    Returns
    -------
    numpy.ndarray, shape (N, 6) or (N, 8)
        The features.
    """
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
