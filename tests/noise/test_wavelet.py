"""Wavelet denoising: median-based sigma, thresholds, thesis zero mode, hybrid DWT+KF, no fake BI."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from imunav.errors import InvalidInputError, NonFiniteError, ShapeError
from imunav.noise import allan_deviation
from imunav.noise.ar import gm_discrete
from imunav.noise.wavelet import compare_hybrid, default_level, mad_sigma, wavelet_denoise

pywt = pytest.importorskip("pywt")


def test_mad_sigma_is_median_based(rng):
    sig = 0.3
    x = np.asarray(pywt.data.demo_signal("Doppler", 4096)) + rng.normal(scale=sig, size=4096)
    assert mad_sigma(x) == pytest.approx(sig, rel=0.1)
    # a few large spikes barely move the median estimate but inflate a mean-based one
    x2 = x.copy()
    x2[::128] += 50.0
    cd1 = pywt.dwt(x2, "db4", mode="periodization")[1]
    assert mad_sigma(x2) == pytest.approx(sig, rel=0.15)
    assert np.mean(np.abs(cd1)) / 0.6745 > 2 * sig


@pytest.mark.parametrize("mode", ["soft", "hard"])
def test_universal_threshold_reduces_error(mode, rng):
    clean = np.asarray(pywt.data.demo_signal("Doppler", 4096))
    noisy = clean + rng.normal(scale=0.1, size=clean.size)
    den = wavelet_denoise(noisy, wavelet="db4", level=5, mode=mode)
    assert den.shape == noisy.shape
    err0 = np.sqrt(np.mean((noisy - clean) ** 2))
    err1 = np.sqrt(np.mean((den - clean) ** 2))
    assert err1 < 0.6 * err0


def test_zero_mode_keeps_only_approximation(rng):
    x = rng.normal(size=(1024, 2))
    den = wavelet_denoise(x, level=3, mode="zero", wavelet="haar")
    # Haar approximation at level 3 = means of blocks of 8 samples
    np.testing.assert_allclose(den[:8, 0], x[:8, 0].mean(), rtol=1e-10)
    np.testing.assert_allclose(den[8:16, 1], x[8:16, 1].mean(), rtol=1e-10)


def test_default_level_band():
    assert default_level(3_600_000, 1000.0) == 9  # 1000/2^10 < 1 Hz
    assert default_level(64, None) >= 1


def test_hybrid_dwt_kf_beats_kf_only(rng):
    fs, n, T, sg, sn = 100.0, 60_000, 20.0, 0.02, 0.2
    phi, q = gm_discrete(T, sg, 1 / fs)
    w = rng.normal(scale=math.sqrt(q), size=n)
    w[0] = rng.normal(scale=sg)
    bias = 0.5 + lfilter([1.0], [1.0, -phi], w)
    y = bias + rng.normal(scale=sn, size=n)
    # the non-causal DWT adds information a causal filter lacks: lower RMSE and MAPE
    r = compare_hybrid(y, bias, fs, T, sg, mode="soft", level=8, skip_s=60.0)
    assert r.rmse_hybrid < r.rmse_kf and r.mape_hybrid < r.mape_kf
    r0 = compare_hybrid(y, bias, fs, T, sg, mode="zero", level=8, skip_s=60.0)
    assert r0.rmse_hybrid < r0.rmse_kf
    assert set(r.to_dict()) >= {"rmse_kf", "rmse_hybrid", "mape_kf", "mape_hybrid"}


def test_denoising_does_not_fake_lower_bias_instability(rng):
    # white noise + Gauss-Markov bias drift: the Allan floor (B region, tau >> approximation band)
    # of the denoised record equals the raw one within its confidence interval.
    fs, n, T, sg = 100.0, 2**19, 30.0, 0.01
    phi, q = gm_discrete(T, sg, 1 / fs)
    w = rng.normal(scale=math.sqrt(q), size=n)
    w[0] = rng.normal(scale=sg)
    y = lfilter([1.0], [1.0, -phi], w) + rng.normal(scale=0.1, size=n)
    den = wavelet_denoise(y, fs, mode="soft")
    ra = allan_deviation(y, fs, [10, 30, 60], ci=0.95)
    rd = allan_deviation(den, fs, [10, 30, 60], ci=0.95)
    assert np.all(rd.adev > ra.adev_lo) and np.all(rd.adev < ra.adev_hi)
    # while the short-tau (white-noise) part is removed: a lower N is expected, not a lower floor
    r1 = allan_deviation(y, fs, [0.02])
    r2 = allan_deviation(den, fs, [0.02])
    assert r2.adev[0] < 0.5 * r1.adev[0]


def test_bad_inputs():
    with pytest.raises(ShapeError):
        wavelet_denoise(np.ones((2, 2, 2)))
    with pytest.raises(NonFiniteError, match="row 2"):
        wavelet_denoise(np.array([1, 2, np.nan, 4, 5, 6, 7, 8, 9.0]))
    with pytest.raises(InvalidInputError, match="mode"):
        wavelet_denoise(np.ones(64), mode="medium")
    with pytest.raises(InvalidInputError, match="wavelet"):
        wavelet_denoise(np.ones(64), wavelet="nope")
    with pytest.raises(InvalidInputError, match="MAPE"):
        compare_hybrid(np.ones(256), np.zeros(256), 10.0, 1.0, 0.1)


def test_without_pywavelets_names_the_extra(monkeypatch):
    """PyWavelets is the `wavelet` extra: imunav.noise imports without it and the wavelet functions say what to
    install."""
    import sys

    from imunav.errors import MissingDependencyError

    for k in [k for k in sys.modules if k == "pywt" or k.startswith("pywt.")]:
        monkeypatch.setitem(sys.modules, k, None)
    with pytest.raises(MissingDependencyError, match=r"pip install 'imunav\[wavelet\]'"):
        wavelet_denoise(np.zeros(256), 100.0)
