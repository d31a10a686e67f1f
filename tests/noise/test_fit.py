"""Noise-term fit: closed forms of every term, truth recovery with honest intervals, selection,
slope read-outs, exports, bad input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.signal import lfilter

from imunav.errors import InsufficientDataError, InvalidInputError
from imunav.noise import allan_deviation, avar_model, fit_noise, write_kalibr_yaml
from imunav.noise.ar import gm_discrete


def flicker(n, B, fs, rng):
    """Rate noise with two-sided PSD B^2/(2 pi f) (FFT shaping of white noise)."""
    z = np.fft.rfft(rng.normal(size=n))
    f = np.fft.rfftfreq(n, 1 / fs)
    s1 = np.zeros_like(f)
    s1[1:] = 2 * B**2 / (2 * np.pi * f[1:])
    return np.fft.irfft(z * np.sqrt(s1 / (2 / fs)), n)


def rel_sd(r):
    return np.sqrt(2.0 / r.edf)


def test_closed_form_each_term(rng):
    fs, n = 10.0, 2**20
    # white phase (quantization): x_k white with variance Q^2
    Q = 1e-3
    xq = rng.normal(scale=Q, size=n + 1)
    r = allan_deviation(xq, fs, [0.1, 0.4, 1.6], input="phase", alpha=2)
    np.testing.assert_allclose(r.avar, avar_model(r.tau, Q=Q), rtol=0.05)
    # white rate (ARW / VRW)
    N = 0.02
    r = allan_deviation(rng.normal(scale=N * np.sqrt(fs), size=n), fs, [0.1, 1.0, 10.0])
    np.testing.assert_allclose(r.avar, avar_model(r.tau, N=N), rtol=0.05)
    # flicker rate (bias instability), tau well inside (10/fs, T/100)
    B = 0.01
    r = allan_deviation(flicker(n, B, fs, rng), fs, [1.6, 3.2, 6.4])
    assert np.all(4 * rel_sd(r) < 0.05)
    np.testing.assert_allclose(r.avar, avar_model(r.tau, B=B), rtol=0.05)
    # random-walk rate
    K = 1e-3
    rw = np.cumsum(rng.normal(scale=K / np.sqrt(fs), size=n))
    r = allan_deviation(rw, fs, [1.0, 2.0, 5.0])
    np.testing.assert_allclose(r.avar, avar_model(r.tau, K=K), rtol=0.05)
    # rate ramp (deterministic: exact)
    R = 1e-4
    r = allan_deviation(R * np.arange(n) / fs, fs, [1.0, 10.0, 100.0])
    np.testing.assert_allclose(r.avar, avar_model(r.tau, R=R), rtol=1e-6)
    # first-order Gauss-Markov rate
    T, s = 5.0, 0.01
    phi, q = gm_discrete(T, s, 1 / fs)
    w = rng.normal(scale=math.sqrt(q), size=n)
    w[0] = rng.normal(scale=s)
    r = allan_deviation(lfilter([1.0], [1.0, -phi], w), fs, [0.5, 2.0, 5.0, 10.0])
    assert np.all(4 * rel_sd(r) < 0.05)
    np.testing.assert_allclose(r.avar, avar_model(r.tau, gm=[(s, T)]), rtol=0.05)


def white_plus_walk(N, K, fs, n, rng):
    return rng.normal(scale=N * np.sqrt(fs), size=n) + np.cumsum(rng.normal(scale=K / np.sqrt(fs), size=n))


def test_truth_recovery_with_intervals(rng):
    # crossover 3 N^2 / K^2 = 48 s inside a 4000 s record; 4 seeded runs
    N, K, fs = 1e-3, 2.5e-4, 100.0
    zs = []
    for seed in range(4):
        y = white_plus_walk(N, K, fs, 400_000, np.random.default_rng(seed))
        f = fit_noise(allan_deviation(y, fs, units="rad/s"))
        for name, truth in (("N", N), ("K", K)):
            i = f.names.index(name)
            assert f.selected[i, 0]
            zs.append((f.value[i, 0] - truth) / f.se[i, 0])
            assert f.ci_lo[i, 0] < f.value[i, 0] < f.ci_hi[i, 0]
    # standardized errors look like N(0, 1): none beyond 3.5 sigma, rms near 1
    zs = np.array(zs)
    assert np.all(np.abs(zs) < 3.5)
    assert 0.3 < np.sqrt(np.mean(zs**2)) < 2.0


def test_selection_white_noise_only(rng):
    N, fs = 0.01, 50.0
    r = allan_deviation(rng.normal(scale=N * np.sqrt(fs), size=200_000), fs, units="m/s^2")
    f = fit_noise(r)
    assert f.selected[:, 0].tolist() == [False, True, False, False, False]
    assert f.get("N") == pytest.approx(N, rel=0.01)
    assert f.quantity == "accel" and f.units[1] == "m/s^2/sqrt(Hz)"
    # slope read-out of N on pure white noise agrees
    assert f.slopes.value[1, 0] == pytest.approx(N, rel=0.02)
    assert f.slopes.found[1, 0]


def test_gauss_markov_term(rng):
    fs, n, T, s, N = 20.0, 400_000, 20.0, 0.01, 0.005
    phi, q = gm_discrete(T, s, 1 / fs)
    w = rng.normal(scale=math.sqrt(q), size=n)
    w[0] = rng.normal(scale=s)
    y = lfilter([1.0], [1.0, -phi], w) + rng.normal(scale=N * np.sqrt(fs), size=n)
    f = fit_noise(allan_deviation(y, fs), terms=("N",), gauss_markov=1, select=None)
    iT, iS = f.names.index("GM1_T"), f.names.index("GM1_sigma")
    assert f.ci_lo[iT, 0] < T < f.ci_hi[iT, 0]
    assert f.value[iS, 0] == pytest.approx(s, rel=0.25)
    assert f.get("N") == pytest.approx(N, rel=0.02)
    np.testing.assert_allclose(f.model_avar([1.0, 10.0]), avar_model([1.0, 10.0], N=f.get("N"),
                               gm=[(f.value[iS, 0], f.value[iT, 0])]))


def test_display_units_and_exports(tmp_path, rng):
    fs = 100.0
    g = white_plus_walk(1e-3, 2.5e-4, fs, 100_000, rng)[:, None] * np.ones((1, 3))
    a = white_plus_walk(2e-3, 1e-4, fs, 100_000, rng)[:, None] * np.ones((1, 3))
    fg = fit_noise(allan_deviation(g, fs, units="rad/s"))
    fa = fit_noise(allan_deviation(a, fs, units="m/s^2"))
    assert fg.display_units[1] == "deg/sqrt(h)"
    np.testing.assert_allclose(fg.display("N"), fg.value[1] * 180 / np.pi * 60)
    p = fg.to_json(tmp_path / "fit.json")
    d = json.loads(p.read_text())
    assert d["terms"]["N"]["display_unit"] == "deg/sqrt(h)" and len(d["terms"]["N"]["value"]) == 3
    y = write_kalibr_yaml(tmp_path / "imu.yaml", fg, fa, update_rate=fs).read_text()
    kv = {ln.split(":")[0]: float(ln.split(":")[1].split("#")[0]) for ln in y.splitlines()
          if ln and not ln.startswith("#") and "rostopic" not in ln}
    assert kv["gyroscope_noise_density"] == pytest.approx(fg.value[1].max())
    assert kv["accelerometer_random_walk"] == pytest.approx(fa.value[3].max())
    assert kv["update_rate"] == fs


def test_bad_inputs(rng):
    r = allan_deviation(rng.normal(size=1000), 1.0)
    with pytest.raises(InvalidInputError, match="terms"):
        fit_noise(r, terms=("N", "X"))
    with pytest.raises(InvalidInputError, match="kind"):
        fit_noise(allan_deviation(rng.normal(size=1000), 1.0, kind="modified"))
    with pytest.raises(InvalidInputError, match="select"):
        fit_noise(r, select="best")
    with pytest.raises(InsufficientDataError, match="tau"):
        fit_noise(r, tau_range=(1e5, 1e6))
    with pytest.raises(InvalidInputError, match="AllanResult"):
        fit_noise(np.ones(3))


def test_a_term_the_record_is_too_short_for_is_not_identifiable():
    """White noise N plus rate random walk K: K rises above N from tau_x = sqrt(3) N / K; a record shorter than
    about 9 tau_x cannot estimate it (issue 26)."""
    from imunav.noise import allan_deviation, fit_noise, identifiability

    fs, n_white, k_rw = 10.0, 1e-3, 2e-5  # tau_x = sqrt(3) * 50 = 87 s: needs about 780 s
    rng = np.random.default_rng(3)
    for seconds, expected in ((120.0, False), (6000.0, True)):
        n = int(seconds * fs)
        x = n_white * np.sqrt(fs) * rng.standard_normal(n) + np.cumsum(k_rw / np.sqrt(fs) * rng.standard_normal(n))
        f = fit_noise(allan_deviation(x, fs), terms=("N", "K"), select=None)
        row = identifiability(f, seconds)["K"][0]
        assert row["identifiable"] is expected, (seconds, row)
        if expected is False:
            assert row["needs_s"] > seconds
        else:
            assert row["needs_s"] == pytest.approx(9 * np.sqrt(3) * n_white / k_rw, rel=0.5)
