"""Calibration of the standard errors that :func:`imunav.noise.fit_noise` reports.

Each test simulates 60 independent channels of known noise terms in one
array (a channel is an independent run), computes the overlapping Allan
deviation of all of them in one call and fits the model that generated them
(``select=None``).  The z-scores (value - truth) / ``NoiseFit.se`` of each term
must have an RMS inside the 99 % chi-square interval for 60 values
(tests/_calibration.py), which rejects a standard error wrong by 1.5 or 1/1.5.

Set IMUNAV_SIGMA_SCALE=1.5 (or 0.6667) to see these tests fail.
"""

from __future__ import annotations

import math

import numpy as np
from _calibration import assert_rms_calibrated, z_scores
from scipy.signal import lfilter

from imunav.noise import allan_deviation, fit_noise
from imunav.noise.ar import gm_discrete

CHANNELS = 60


def _check(fit, truths: dict[str, float], where: str) -> None:
    for name, truth in truths.items():
        i = fit.names.index(name)
        assert fit.selected[i].all(), f"{where}: {name} not kept"
        assert_rms_calibrated(z_scores(fit.value[i], truth, fit.se[i]), f"{where} {name}")


def test_white_plus_random_walk_se_calibrated():
    """N (white rate) and K (random-walk rate), crossover 3 N^2/K^2 = 48 s in a 1000 s record."""
    N, K, fs, n = 1e-3, 2.5e-4, 100.0, 100_000
    rng = np.random.default_rng(11)
    y = rng.normal(scale=N * math.sqrt(fs), size=(n, CHANNELS))
    y += np.cumsum(rng.normal(scale=K / math.sqrt(fs), size=(n, CHANNELS)), axis=0)
    f = fit_noise(allan_deviation(y, fs, units="rad/s"), terms=("N", "K"), select=None, slopes=False)
    _check(f, {"N": N, "K": K}, "white + random walk")


def test_white_plus_flicker_se_calibrated():
    """N and B (flicker rate, PSD B^2/(2 pi f), FFT-shaped)."""
    N, B, fs, n = 1e-3, 5e-4, 100.0, 2**17
    rng = np.random.default_rng(12)
    f_hz = np.fft.rfftfreq(n, 1 / fs)
    psd = np.zeros_like(f_hz)
    psd[1:] = 2 * B**2 / (2 * np.pi * f_hz[1:])
    flick = np.fft.irfft(np.fft.rfft(rng.normal(size=(n, CHANNELS)), axis=0) * np.sqrt(psd / (2 / fs))[:, None],
                         n, axis=0)
    y = rng.normal(scale=N * math.sqrt(fs), size=(n, CHANNELS)) + flick
    f = fit_noise(allan_deviation(y, fs, units="rad/s"), terms=("N", "B"), select=None, slopes=False)
    _check(f, {"N": N, "B": B}, "white + flicker")


def test_gauss_markov_se_calibrated():
    """N plus one Gauss-Markov term: sigma and the fitted correlation time T (250 T per record).

    se(sigma) must include the uncertainty of T (sigma^2 and T trade off): with
    T held fixed it came out 1.44 x too small here (z RMS 1.43)."""
    fs, n, T, s, N = 10.0, 50_000, 20.0, 0.01, 0.005
    rng = np.random.default_rng(13)
    phi, q = gm_discrete(T, s, 1 / fs)
    w = rng.normal(scale=math.sqrt(q), size=(n, CHANNELS))
    w[0] = rng.normal(scale=s, size=CHANNELS)
    y = lfilter([1.0], [1.0, -phi], w, axis=0) + rng.normal(scale=N * math.sqrt(fs), size=(n, CHANNELS))
    f = fit_noise(allan_deviation(y, fs), terms=("N",), gauss_markov=1, select=None, slopes=False)
    _check(f, {"N": N, "GM1_sigma": s, "GM1_T": T}, "white + Gauss-Markov")
