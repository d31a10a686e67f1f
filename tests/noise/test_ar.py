"""AR / Gauss-Markov: Yule-Walker sign convention, T_c guards, 1/e rule, noise bias, decimation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.noise.ar import (
    ar1_correlation_time,
    ar1_noise_bias,
    autocorrelation,
    block_decimate,
    correlation_time_acf,
    fit_gauss_markov,
    gm_discrete,
    yule_walker,
)


def ar_series(c, n, rng, sigma_w=1.0):
    w = rng.normal(scale=sigma_w, size=n + 500)
    return lfilter([1.0], np.concatenate(([1.0], -np.asarray(c))), w)[500:]


def gm_series(T, sigma, dt, n, rng):
    phi, q = gm_discrete(T, sigma, dt)
    w = rng.normal(scale=math.sqrt(q), size=n)
    w[0] = rng.normal(scale=sigma)  # start in the stationary distribution
    return lfilter([1.0], [1.0, -phi], w)


def test_autocorrelation_matches_direct(rng):
    x = rng.normal(size=300)
    r = autocorrelation(x, 5)
    xm = x - x.mean()
    direct = [np.dot(xm[: 300 - k], xm[k:]) / 300 for k in range(6)]
    np.testing.assert_allclose(r, direct, rtol=1e-10, atol=1e-12)
    assert autocorrelation(x, 3, normalize=True)[0] == pytest.approx(1.0)


def test_yule_walker_sign_convention_ar2(rng):
    c = np.array([0.6, 0.25])  # x_k = 0.6 x_{k-1} + 0.25 x_{k-2} + w_k
    x = ar_series(c, 200_000, rng)
    m = yule_walker(x, 2)
    # c = R^-1 r (no minus sign); sd of each coefficient ~ sqrt((1 - c2^2)/n) ~ 0.002
    np.testing.assert_allclose(m.c, c, atol=0.01)
    assert m.sigma_w2 == pytest.approx(1.0, rel=0.02)


def test_gm_discrete_is_stationary():
    phi, q = gm_discrete(10.0, 2.0, 0.1)
    assert phi == pytest.approx(math.exp(-0.01))
    # stationary variance q / (1 - phi^2) equals sigma^2 (needs the factor 2 of the corrected eq. 7)
    assert q / (1 - phi**2) == pytest.approx(4.0, rel=1e-12)


def test_gm_correlation_time_recovered(rng):
    T, sigma, fs = 2.0, 0.5, 10.0
    x = gm_series(T, sigma, 1 / fs, 200_000, rng)
    g = fit_gauss_markov(x, fs)
    # sd of c1 ~ sqrt((1-c1^2)/n) -> sd(T)/T ~ 1.4 %; 5 % is > 3 sd
    assert g.T == pytest.approx(T, rel=0.05)
    assert g.sigma == pytest.approx(sigma, rel=0.05)
    assert g.T_acf == pytest.approx(T, rel=0.1)  # the 1/e rule, noisier
    assert correlation_time_acf(x, fs) == pytest.approx(g.T_acf)


def test_white_noise_bias_and_decimation(rng):
    # GM at 1 kHz plus white noise: c1 is pulled down as predicted; block decimation restores T
    T, sg, sn, fs = 5.0, 0.01, 0.05, 1000.0
    n = 400_000
    gm = gm_series(T, sg, 1 / fs, n, rng)
    y = gm + rng.normal(scale=sn, size=n)
    c1 = yule_walker(y, 1).c[0]
    assert c1 == pytest.approx(ar1_noise_bias(sg, sn, T, 1 / fs), abs=0.01)
    T_raw = ar1_correlation_time(c1, 1 / fs)
    assert T_raw < 0.01 * T  # hopelessly biased
    g = fit_gauss_markov(y, fs, decimate=1000)
    assert g.T == pytest.approx(T, rel=0.35)  # 80 s record / 5 s -> few correlation times


def test_guards():
    assert ar1_correlation_time(0.5, 0.1) == pytest.approx(-0.1 / math.log(0.5))
    with pytest.raises(InvalidInputError, match="c1 <= 0"):
        ar1_correlation_time(-0.2, 0.1)
    with pytest.raises(InvalidInputError, match="not stationary"):
        ar1_correlation_time(1.0, 0.1)
    assert math.isnan(ar1_correlation_time(1.2, 0.1, on_invalid="nan"))
    with pytest.raises(InvalidInputError, match="c1 <= 0"):
        fit_gauss_markov((-1.0) ** np.arange(100), 1.0)


def test_bad_inputs():
    with pytest.raises(ShapeError):
        yule_walker(np.ones((10, 2)))
    with pytest.raises(NonFiniteError, match="index 3"):
        autocorrelation([1, 2, 3, np.nan])
    with pytest.raises(InvalidInputError, match="order"):
        yule_walker(np.arange(10.0), 0)
    with pytest.raises(InsufficientDataError):
        yule_walker(np.arange(2.0), 3)
    with pytest.raises(InvalidInputError, match="constant"):
        yule_walker(np.ones(10))
    with pytest.raises(InsufficientDataError):
        block_decimate(np.ones(5), 4)
