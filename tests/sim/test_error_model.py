"""Virtual-IMU error model: noise statistics against closed forms, exact
deterministic part, reproducibility, bad input.

Allan variances are computed with an independent numpy overlapping AVAR
written here (not imunav.noise); tolerances come from the equivalent degrees
of freedom of the overlapping estimator (Greenhall & Riley, via
``allantools.edf_greenhall``): the relative standard deviation of an AVAR
estimate is sqrt(2 / edf), and every tolerance below is at least 3.5 of those.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import static_imu

from imunav.errors import (
    ConfigError,
    FileFormatError,
    InsufficientDataError,
    InvalidInputError,
    NonFiniteError,
    ShapeError,
    UnitError,
)
from imunav.sim.error_model import (
    BIAS_INSTABILITY_FLOOR,
    Flicker,
    GaussMarkov,
    ImuErrorModel,
    TriadErrors,
    allan_variance_gauss_markov,
    allan_variance_ieee952,
    apply_errors,
    scale_misalignment_matrix,
)
from imunav.timeseries import ImuData
from imunav.units import DEG, G0

allantools = pytest.importorskip("allantools")


def static(n: int, fs: float, accel=(0.0, 0.0, -G0)) -> ImuData:
    """The ideal (noise-free) recording at rest."""
    return static_imu(n, fs, accel=accel, gyro_sd=0.0, accel_sd=0.0)


def oavar(y: np.ndarray, fs: float, m: int) -> float:
    """Overlapping Allan variance of rate samples y at tau = m / fs (IEEE 952 / NIST SP 1065 eq. 11)."""
    y = np.asarray(y, float) - np.mean(y)
    x = np.concatenate([[0.0], np.cumsum(y)]) / fs  # integrated rate ("phase")
    tau = m / fs
    d = x[2 * m :] - 2.0 * x[m:-m] + x[: -2 * m]
    return float(np.sum(d * d) / (2.0 * tau**2 * d.size))


def rel_sigma(alpha: int, m: int, n: int) -> float:
    """Relative standard deviation of the overlapping AVAR for power-law noise alpha."""
    edf = allantools.edf_greenhall(alpha=alpha, d=2, m=m, N=n + 1, overlapping=True, modified=False)
    return math.sqrt(2.0 / edf)


def gyro_only(**kw) -> ImuErrorModel:
    return ImuErrorModel(gyro=TriadErrors(**kw))


# --------------------------------------------------------------------------
# white noise
# --------------------------------------------------------------------------
def test_white_noise_density_gives_sigma_n_sqrt_fs():
    fs, n = 200.0, 100_000
    nd_g, nd_a = 0.0057 * DEG, 0.00043 * G0  # thesis Table 5.1 / 5.2 densities
    model = ImuErrorModel(gyro=TriadErrors(noise_density=nd_g), accel=TriadErrors(noise_density=nd_a))
    out = apply_errors(static(n, fs), model, rng=1)
    # per-sample sigma = n sqrt(fs); std of a sample std is sigma / sqrt(2N) = 0.22 %, far inside 3 %
    np.testing.assert_allclose(out.gyro.std(axis=0), nd_g * math.sqrt(fs), rtol=0.03)
    np.testing.assert_allclose((out.accel - out.accel.mean(0)).std(axis=0), nd_a * math.sqrt(fs), rtol=0.03)


def test_white_noise_allan_N():
    fs, n, nd = 100.0, 400_000, 2e-3
    y = apply_errors(static(n, fs), gyro_only(noise_density=nd), rng=7).gyro
    for m in (10, 100):
        tol = 4.0 * rel_sigma(0, m, n)
        for i in range(3):
            assert oavar(y[:, i], fs, m) == pytest.approx(nd**2 / (m / fs), rel=tol)


# --------------------------------------------------------------------------
# Gauss-Markov
# --------------------------------------------------------------------------
@pytest.mark.parametrize("seed", [11, 12, 13])
def test_gauss_markov_matches_closed_form_allan(seed):
    # T_c = 1 s at 50 Hz over 20,000 s (1e6 samples), one axis per seed.  At
    # tau <= T_c the estimator behaves at worst like random-walk FM
    # (alpha = -2); its edf at tau = T_c (m = 50) gives a relative sigma of
    # 1.04 %, so 5 % is > 4.5 sigma (asserted below), and tau >= 10 samples
    # keeps sample averages within ~0.6 % of continuous averages.  Observed
    # over 24 realisations: relative std 0.4 / 0.7 / 1.0 % at m = 10 / 25 / 50,
    # largest deviation 2.7 %.
    fs, n, sigma, tc = 50.0, 1_000_000, 1e-3, 1.0
    model = gyro_only(bias_instability=GaussMarkov([sigma, 0.0, 0.0], tc))
    y = apply_errors(static(n, fs), model, rng=seed).gyro[:, 0]
    for m in (10, 25, 50):
        tau = m / fs
        assert 4.5 * rel_sigma(-2, m, n) < 0.05
        expected = float(allan_variance_gauss_markov(tau, sigma, tc))
        assert oavar(y, fs, m) == pytest.approx(expected, rel=0.05)


def test_gauss_markov_exact_discretisation_variance_and_lag1():
    # sigma_w^2 = sigma^2 (1 - phi^2): the stationary variance is sigma^2.  With the
    # thesis's printed eq. 7 (1 - phi) it would be sigma^2 / (1 + phi) ~ sigma^2 / 2.
    fs, n, sigma, tc = 10.0, 1_000_000, 0.5, 0.5
    y = apply_errors(static(n, fs), gyro_only(bias_instability=GaussMarkov(sigma, tc)), rng=3).gyro
    phi = math.exp(-1.0 / (fs * tc))
    for i in range(3):
        v = y[:, i]
        # var of the sample variance of an AR(1): 2 sigma^4 (1 + phi^2) / ((1 - phi^2) N) -> ~0.2 %
        assert v.var() == pytest.approx(sigma**2, rel=0.02)
        r1 = np.dot(v[1:] - v.mean(), v[:-1] - v.mean()) / ((n - 1) * v.var())
        assert r1 == pytest.approx(phi, abs=0.01)


def test_gauss_markov_closed_form_limits():
    # tau << T: random walk with K^2 = 2 sigma^2 / T -> 2 sigma^2 tau / (3 T); tau >> T: white, sigma^2 T... / tau
    s, tc = 2.0, 5.0
    assert allan_variance_gauss_markov(1e-4, s, tc) == pytest.approx(2 * s**2 * 1e-4 / (3 * tc), rel=1e-4)
    assert allan_variance_gauss_markov(1e5, s, tc) == pytest.approx(2 * s**2 * tc / 1e5, rel=1e-3)
    # continuity across the series switch at tau / T = 1e-2
    a, b = allan_variance_gauss_markov([0.0499999, 0.0500001], s, tc)
    assert a == pytest.approx(b, rel=1e-5)


# --------------------------------------------------------------------------
# IEEE-952 terms
# --------------------------------------------------------------------------
def test_rate_random_walk_allan_K():
    fs, n, k = 10.0, 500_000, 1e-3
    y = apply_errors(static(n, fs), gyro_only(random_walk=[0.0, k, 0.0]), rng=5).gyro
    assert np.all(y[:, [0, 2]] == 0)
    for m in (20, 100):
        tau = m / fs
        tol = 4.0 * rel_sigma(-2, m, n)
        expected = k**2 * tau / 3.0 + k**2 / fs / (6 * m)  # discrete walk: + K^2 dt / (6 m)
        assert oavar(y[:, 1], fs, m) == pytest.approx(expected, rel=tol)


def test_rate_ramp_allan_R_is_exact():
    fs, n, r = 10.0, 20_000, np.array([1e-4, -2e-4, 3e-4])
    y = apply_errors(static(n, fs), gyro_only(rate_ramp=r), rng=0).gyro
    np.testing.assert_allclose(y[:, 0], r[0] * np.arange(n) / fs, rtol=1e-12, atol=1e-18)
    for m in (10, 1000):
        tau = m / fs
        for i in range(3):
            assert oavar(y[:, i], fs, m) == pytest.approx(float(allan_variance_ieee952(tau, R=r[i])), rel=1e-6)


def test_integrated_quantization_allan_Q():
    # Delta-angle style output: LSB q with the residue carried; Q = q dt / sqrt(12).
    # A white input of sigma = q/2 makes the residue uniform and white (characteristic
    # function at 2 pi / q: exp(-pi^2 / 2) = 0.007), and adds N^2 / tau.
    fs, n, q = 100.0, 400_000, 1e-3
    nd = 0.5 * q / math.sqrt(fs)
    model = gyro_only(noise_density=nd, quantization=q, quantization_mode="integrated")
    y = apply_errors(static(n, fs), model, rng=9).gyro
    assert np.allclose(np.round(y / q) * q, y, atol=1e-15)  # outputs are whole LSBs
    qq = q / fs / math.sqrt(12.0)
    for m in (1, 2, 4):
        tau = m / fs
        expected = float(allan_variance_ieee952(tau, Q=qq, N=nd))
        assert 3.0 * qq**2 / tau**2 > 0.1 * expected  # the Q term is a visible part
        tol = 4.0 * rel_sigma(0, max(m, 2), n) + 0.01
        for i in range(3):
            assert oavar(y[:, i], fs, m) == pytest.approx(expected, rel=tol)
    assert model.gyro.allan_variance([0.01], dt=1 / fs)[0, 0] == pytest.approx(
        float(allan_variance_ieee952(0.01, Q=qq, N=nd)), rel=1e-12
    )


def test_rate_quantization_and_saturation():
    fs, n, q, fsc = 100.0, 5000, 0.01, 0.05
    t = np.arange(n) / fs
    x = np.column_stack([0.1 * np.sin(2 * np.pi * 0.3 * t), 0.0123 * np.ones(n), -0.2 * np.ones(n)])
    ideal = ImuData(t, x, np.zeros((n, 3)))
    model = gyro_only(quantization=q, full_scale=fsc)
    out, truth = apply_errors(ideal, model, rng=0, return_truth=True)
    assert np.allclose(out.gyro / q, np.round(out.gyro / q), atol=1e-9)
    assert np.all(np.abs(out.gyro) <= fsc + 1e-15)
    expected = np.clip(q * np.floor(x / q + 0.5), -fsc, fsc)
    np.testing.assert_allclose(out.gyro, expected, atol=1e-15)
    quantized = q * np.floor(x / q + 0.5)
    assert truth.gyro.n_saturated.tolist() == [int(np.sum(np.abs(quantized[:, 0]) > fsc)), 0, n]


def test_flicker_model_has_flat_floor_0_6643_B():
    f = Flicker(b=1.0, tau_min=0.1, tau_max=100.0)
    taus = np.logspace(-1, 2, 40)
    adev = np.sqrt(f.allan_variance(taus)[0])
    np.testing.assert_allclose(adev, BIAS_INSTABILITY_FLOOR, rtol=0.005)
    assert f.floor_ripple < 0.005
    assert BIAS_INSTABILITY_FLOOR == pytest.approx(0.6643, abs=1e-4)


def test_flicker_bias_instability_allan_B():
    # Flat floor 0.6643 B over [0.2, 100] s; flicker FM (alpha = -1) edf at
    # tau = 1 s and 10 s over 1e6 samples gives relative sigma 0.9 % and 2.9 %.
    fs, n, b = 50.0, 1_000_000, 1e-3
    y = apply_errors(static(n, fs), gyro_only(bias_instability=Flicker([0.0, 0.0, b], 0.2, 100.0)), rng=21).gyro
    for m in (50, 500):
        tol = 4.0 * rel_sigma(-1, m, n) + 0.005  # + model ripple
        assert tol < 0.13
        assert oavar(y[:, 2], fs, m) == pytest.approx((BIAS_INSTABILITY_FLOOR * b) ** 2, rel=tol)


# --------------------------------------------------------------------------
# deterministic part
# --------------------------------------------------------------------------
def _deterministic_model() -> ImuErrorModel:
    gyro = TriadErrors(
        bias=[0.02, -0.01, 0.03],
        scale_misalignment=scale_misalignment_matrix([0.019, 0.032, 0.015], [8e-3, 4e-3, 5e-3, 6.5e-3, 6.2e-3, 7.4e-3]),
        bias_temp_poly=[[1e-4, -2e-4, 3e-4], [1e-6, 2e-6, -1e-6]],
        scale_temp_poly=[[1e-5, 2e-5, -3e-5]],
    )
    accel = TriadErrors(
        bias=[0.3, -0.2, 0.1],
        scale_misalignment=scale_misalignment_matrix([0.021, 0.017, 0.018], np.array([[0, 7, 4], [5, 0, 4], [6, 8, 0]]) * 1e-3),
        bias_temp_poly=[[2e-4, 1e-4, -1e-4]],
        scale_temp_poly=[[1e-5, -1e-5, 2e-5], [1e-7, 1e-7, 1e-7]],
    )
    g = np.array([[8e-4, 1e-4, -2e-4], [5e-5, 1e-3, 3e-5], [-1e-4, 2e-4, 7e-4]])
    return ImuErrorModel(gyro=gyro, accel=accel, g_sensitivity=g, temp_ref_c=20.0)


def test_deterministic_part_exact():
    rng = np.random.default_rng(0)
    n = 2000
    t = np.arange(n) * 0.01
    w = rng.uniform(-5, 5, (n, 3))
    f = rng.uniform(-20, 20, (n, 3))
    temp = rng.uniform(-30, 50, n)
    ideal = ImuData(t, w, f)
    model = _deterministic_model()
    out = apply_errors(ideal, model, rng=1, temp_c=temp)
    d = temp - model.temp_ref_c
    for te, x, y in ((model.gyro, w, out.gyro), (model.accel, f, out.accel)):
        b = te.bias + d[:, None] * te.bias_temp_poly[0] + (d[:, None] ** 2 * te.bias_temp_poly[1] if len(te.bias_temp_poly) > 1 else 0)
        s = sum(d[:, None] ** (k + 1) * te.scale_temp_poly[k] for k in range(len(te.scale_temp_poly)))
        expected = x @ te.scale_misalignment.T + s * x + b
        if te is model.gyro:
            expected = expected + f @ model.g_sensitivity.T
        np.testing.assert_allclose(y, expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(out.temp, temp)
    assert out.meta["error_model"] == "custom"


def test_diagonal_g_sensitivity_and_no_temperature():
    n = 10
    f = np.tile([1.0, 2.0, -9.8], (n, 1))
    ideal = ImuData(np.arange(n) * 0.1, np.zeros((n, 3)), f)
    model = ImuErrorModel(g_sensitivity=[1e-3, 2e-3, 3e-3])
    out = apply_errors(ideal, model)
    np.testing.assert_allclose(out.gyro, f * [1e-3, 2e-3, 3e-3], atol=1e-15)
    np.testing.assert_array_equal(out.accel, f)


def test_truth_reconstructs_output():
    fs, n = 100.0, 20_000
    te = TriadErrors(
        bias=[0.1, 0.2, 0.3],
        noise_density=1e-3,
        bias_instability=GaussMarkov(1e-3, 5.0),
        random_walk=1e-4,
        rate_ramp=1e-5,
        bias_temp_poly=[[1e-3, 1e-3, 1e-3]],
    )
    model = ImuErrorModel(gyro=te, accel=te, g_sensitivity=np.eye(3) * 1e-3)
    ideal = static(n, fs)
    out, tr = apply_errors(ideal, model, rng=4, temp_c=30.0, return_truth=True)
    expected = ideal.gyro + tr.gyro.bias + tr.gyro.white_noise + ideal.accel @ model.g_sensitivity.T
    np.testing.assert_allclose(out.gyro, expected, atol=1e-12)
    np.testing.assert_allclose(
        tr.gyro.bias, te.bias + 5e-3 + tr.gyro.bias_instability + tr.gyro.random_walk + tr.gyro.rate_ramp, atol=1e-12
    )
    assert np.all(tr.gyro.random_walk[0] == 0)
    assert tr.accel.white_noise.std() == pytest.approx(1e-3 * 10, rel=0.03)


# --------------------------------------------------------------------------
# reproducibility and independence
# --------------------------------------------------------------------------
def _noisy() -> ImuErrorModel:
    te = TriadErrors(noise_density=1e-3, bias_instability=GaussMarkov(1e-3, 1.0), random_walk=1e-4)
    return ImuErrorModel(gyro=te, accel=te)


def test_same_seed_same_output_and_threads_do_not_matter():
    ideal = static(250_000, 100.0)  # above the threading threshold
    model = ImuErrorModel(gyro=TriadErrors(noise_density=1e-3), accel=TriadErrors(random_walk=[0, 1e-3, 0]))
    a = apply_errors(ideal, model, rng=42)
    b = apply_errors(ideal, model, rng=42, threads=1)
    c = apply_errors(ideal, model, rng=43)
    np.testing.assert_array_equal(a.gyro, b.gyro)
    np.testing.assert_array_equal(a.accel, b.accel)
    assert not np.allclose(a.gyro, c.gyro)
    g1 = apply_errors(ideal.slice(0, 1000), _noisy(), rng=np.random.default_rng(5))
    g2 = apply_errors(ideal.slice(0, 1000), _noisy(), rng=np.random.default_rng(5))
    np.testing.assert_array_equal(g1.gyro, g2.gyro)


def test_adding_a_process_keeps_other_streams():
    ideal = static(5000, 100.0)
    base = ImuErrorModel(gyro=TriadErrors(noise_density=1e-3))
    more = ImuErrorModel(gyro=TriadErrors(noise_density=1e-3, random_walk=1e-3), accel=TriadErrors(noise_density=1e-2))
    _, t1 = apply_errors(ideal, base, rng=8, return_truth=True)
    _, t2 = apply_errors(ideal, more, rng=8, return_truth=True)
    np.testing.assert_array_equal(t1.gyro.white_noise, t2.gyro.white_noise)


def test_axes_and_sensors_uncorrelated():
    n = 200_000
    _, tr = apply_errors(static(n, 100.0), _noisy(), rng=3, return_truth=True)
    w = np.hstack([tr.gyro.white_noise, tr.accel.white_noise])
    c = np.corrcoef(w.T)
    off = c[~np.eye(6, dtype=bool)]
    assert np.max(np.abs(off)) < 4.5 / math.sqrt(n)  # |r| ~ N(0, 1/N) under independence
    gm = np.hstack([tr.gyro.bias_instability, tr.accel.bias_instability])
    # increments of the GM tracks are independent innovations
    c2 = np.corrcoef(np.diff(gm, axis=0).T)
    assert np.max(np.abs(c2[~np.eye(6, dtype=bool)])) < 4.5 / math.sqrt(n)


# --------------------------------------------------------------------------
# serialisation
# --------------------------------------------------------------------------
def test_to_dict_from_dict_roundtrip_and_display_units(tmp_path):
    m = _deterministic_model().replace(
        gyro=TriadErrors(noise_density=1e-4, bias_instability=Flicker(1e-5, 1.0, 100.0), quantization=1e-4, full_scale=5.0)
    )
    assert ImuErrorModel.from_dict(m.to_dict()) == m
    assert m.to_dict()["units"]["gyro"]["noise_density"] == "rad/s/sqrt(Hz)"
    d = {
        "name": "x",
        "gyro": {"noise_density": 0.1, "bias_instability": {"model": "gauss_markov", "sigma": 3.0, "tau": {"value": 2, "unit": "min"}},
                 "scale_factor": [100, 200, 300], "misalignment": [1, 2, 3, 4, 5, 6], "bias": {"value": [1, 2, 3], "unit": "deg/s"}},
        "accel": {"bias": [50, 60, 70], "noise_density": 25.0},
        "g_sensitivity": [0.1, 0.1, 0.1],
        "units": {
            "gyro": {"noise_density": "deg/sqrt(h)", "bias_instability": "deg/h", "scale_factor": "ppm", "misalignment": "mrad"},
            "accel": {"bias": "ug", "noise_density": "ug/sqrt(Hz)"},
            "g_sensitivity": "(deg/s)/g",
        },
    }
    m2 = ImuErrorModel.from_dict(d)
    assert m2.gyro.noise_density[0] == pytest.approx(0.1 * DEG / 60)
    assert m2.gyro.bias_instability.sigma[0] == pytest.approx(3.0 * DEG / 3600)
    assert m2.gyro.bias_instability.tau[0] == pytest.approx(120.0)
    assert m2.gyro.scale_factor[2] == pytest.approx(300e-6)
    assert m2.gyro.misalignment[2, 1] == pytest.approx(6e-3)
    assert m2.gyro.bias[1] == pytest.approx(2 * DEG)
    assert m2.accel.bias[0] == pytest.approx(50e-6 * G0)
    assert m2.accel.noise_density[0] == pytest.approx(25e-6 * G0)
    assert m2.g_sensitivity[1, 1] == pytest.approx(0.1 * DEG / G0)
    p = m2.to_toml(tmp_path / "m.toml")
    assert ImuErrorModel.from_toml(p) == m2
    (tmp_path / "d.toml").write_text('name = "disp"\n[gyro]\nnoise_density = 0.15\n[units.gyro]\nnoise_density = "deg/sqrt(h)"\n')
    assert ImuErrorModel.from_toml(tmp_path / "d.toml").gyro.noise_density[0] == pytest.approx(0.15 * DEG / 60)


# --------------------------------------------------------------------------
# bad input
# --------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make, exc, match",
    [
        (lambda: GaussMarkov(-1.0, 1.0), InvalidInputError, "sigma.*>= 0"),
        (lambda: GaussMarkov(1.0, 0.0), InvalidInputError, "tau.*> 0"),
        (lambda: GaussMarkov(1.0, [1.0, -2.0, 1.0]), InvalidInputError, "tau"),
        (lambda: GaussMarkov([1.0, 2.0], 1.0), ShapeError, "sigma.*shape \\(2,\\)"),
        (lambda: GaussMarkov(np.nan, 1.0), NonFiniteError, "finite"),
        (lambda: Flicker(-1e-3), InvalidInputError, "Flicker.b"),
        (lambda: Flicker(1e-3, tau_min=10.0, tau_max=1.0), InvalidInputError, "tau_max"),
        (lambda: Flicker(1e-3, tau_min=0.0), InvalidInputError, "tau_min"),
        (lambda: TriadErrors(bias=[1, 2]), ShapeError, "bias"),
        (lambda: TriadErrors(scale_misalignment=np.eye(2)), ShapeError, "scale_misalignment.*3x3"),
        (lambda: TriadErrors(noise_density=-1.0), InvalidInputError, "noise_density"),
        (lambda: TriadErrors(random_walk=[0, -1, 0]), InvalidInputError, "random_walk"),
        (lambda: TriadErrors(quantization=-1e-3), InvalidInputError, "quantization"),
        (lambda: TriadErrors(full_scale=0.0), InvalidInputError, "full_scale"),
        (lambda: TriadErrors(bias_temp_poly=[1.0, 2.0, 3.0]), ShapeError, "bias_temp_poly.*\\(K, 3\\)"),
        (lambda: TriadErrors(bias_instability=1e-3), InvalidInputError, "GaussMarkov"),
        (lambda: TriadErrors(quantization_mode="delta"), InvalidInputError, "quantization_mode"),
        (lambda: ImuErrorModel(g_sensitivity=np.zeros((2, 3))), ShapeError, "g_sensitivity"),
        (lambda: ImuErrorModel(gyro="x"), InvalidInputError, "TriadErrors"),
        (lambda: ImuErrorModel(temp_ref_c=float("nan")), InvalidInputError, "temp_ref_c"),
        (lambda: scale_misalignment_matrix(0.0, np.eye(3)), InvalidInputError, "diagonal"),
        (lambda: scale_misalignment_matrix(0.0, [1, 2, 3]), ShapeError, "misalignment"),
        (lambda: ImuErrorModel.from_dict({"gyro": {"nois_density": 1.0}}), ConfigError, "nois_density"),
        (lambda: ImuErrorModel.from_dict({"gyroscope": {}}), ConfigError, "gyroscope"),
        (lambda: ImuErrorModel.from_dict({"gyro": {"bias": 1.0}, "units": {"gyro": {"bias": "furlong"}}}), UnitError, "furlong"),
        (lambda: ImuErrorModel.from_dict({"gyro": {"bias_instability": {"model": "pink", "b": 1}}}), ConfigError, "pink"),
        (lambda: ImuErrorModel.from_dict({"gyro": {"bias_instability": {"sigma": 1}}}), ConfigError, "tau"),
    ],
)
def test_bad_parameters_raise(make, exc, match):
    with pytest.raises(exc, match=match):
        make()


def test_bad_files_and_call_arguments(tmp_path):
    with pytest.raises(FileFormatError, match="not found"):
        ImuErrorModel.from_toml(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[gyro\nbias = 1")
    with pytest.raises(ConfigError, match="bad.toml.*not valid TOML"):
        ImuErrorModel.from_toml(bad)
    wrong = tmp_path / "wrong.toml"
    wrong.write_text("[gyro]\nbias = [1, 2]\n")
    with pytest.raises(ShapeError, match="wrong.toml.*bias"):
        ImuErrorModel.from_toml(wrong)
    ideal = static(100, 10.0)
    with pytest.raises(InvalidInputError, match="ImuErrorModel"):
        apply_errors(ideal, "thesis_sim")
    with pytest.raises(InvalidInputError, match="seed"):
        apply_errors(ideal, ImuErrorModel(), rng=-1)
    with pytest.raises(InvalidInputError, match="rng"):
        apply_errors(ideal, ImuErrorModel(), rng="abc")
    with pytest.raises(ShapeError, match="temp_c"):
        apply_errors(ideal, ImuErrorModel(), temp_c=np.zeros(7))
    with pytest.raises(NonFiniteError, match="temp_c.*rows \\[3\\]"):
        apply_errors(ideal, ImuErrorModel(), temp_c=np.where(np.arange(100) == 3, np.nan, 20.0))
    with pytest.raises(InsufficientDataError, match="2 samples"):
        apply_errors(static(1, 10.0), gyro_only(noise_density=1e-3))
    with pytest.raises(InvalidInputError, match="ImuData"):
        apply_errors(np.zeros((10, 7)), ImuErrorModel())


def test_simulate_imu_uses_ideal_imu():
    traj_mod = pytest.importorskip("imunav.sim.trajectory")
    from imunav.sim.error_model import simulate_imu

    n = 200
    t = np.arange(n) / 100.0
    q = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    traj = traj_mod.Trajectory(t, q)
    model = ImuErrorModel(accel=TriadErrors(bias=[0.1, 0.2, 0.3]))
    out = simulate_imu(traj, model, rng=0, earth_rate=False, transport_rate=False, gravity="constant")
    ideal = traj_mod.ideal_imu(traj, earth_rate=False, transport_rate=False, gravity="constant")
    np.testing.assert_allclose(out.accel, ideal.accel + [0.1, 0.2, 0.3], atol=1e-12)


def test_stream_normals_are_standard_normal():
    # In-kernel xoshiro256++ / ziggurat generator: KS test, moments, both tails
    # and the tail region beyond the ziggurat base r = 3.654 (Marsaglia's tail method).
    from scipy import stats

    from imunav.sim._kernels import _ZIG_R
    from imunav.sim.error_model import normals, seed_sequence

    n = 2_000_000
    z = normals(seed_sequence(123), (0, 0, 0, 0), n)
    assert stats.kstest(z[:200_000], "norm").pvalue > 1e-3
    assert abs(z.mean()) < 5 / math.sqrt(n)
    assert z.var() == pytest.approx(1.0, abs=5 * math.sqrt(2 / n))
    assert abs(stats.skew(z)) < 5 * math.sqrt(6 / n)
    assert abs(stats.kurtosis(z)) < 5 * math.sqrt(24 / n)
    for x0 in (1.0, 2.5, _ZIG_R, 4.2):
        p = 2 * stats.norm.sf(x0)
        cnt = np.sum(np.abs(z) > x0)
        assert abs(cnt - n * p) < 5 * math.sqrt(n * p) + 2
    assert np.sum(z > _ZIG_R) > 0 and np.sum(z < -_ZIG_R) > 0
    # streams with different keys are different; the same key repeats
    z2 = normals(seed_sequence(123), (0, 0, 1, 0), 1000)
    assert abs(np.corrcoef(z[:1000], z2)[0, 1]) < 0.15
    np.testing.assert_array_equal(normals(seed_sequence(123), (0, 0, 0, 0), 1000), z[:1000])


def test_non_uniform_time_steps():
    # jittered time stamps: white noise scales with 1/sqrt(dt_k), GM stays stationary
    r = np.random.default_rng(2)
    n = 200_000
    t = np.cumsum(r.uniform(0.005, 0.015, n))
    ideal = ImuData(t, np.zeros((n, 3)), np.zeros((n, 3)))
    nd, sigma = 1e-3, 0.2
    model = ImuErrorModel(gyro=TriadErrors(noise_density=nd), accel=TriadErrors(bias_instability=GaussMarkov(sigma, 0.05)))
    out = apply_errors(ideal, model, rng=1)
    dt = np.diff(t, prepend=t[0] - (t[1] - t[0]))
    np.testing.assert_allclose((out.gyro * np.sqrt(dt)[:, None] / nd).std(axis=0), 1.0, rtol=0.01)
    np.testing.assert_allclose(out.accel.std(axis=0), sigma, rtol=0.03)


def test_common_axis_noise_option_reproduces_shared_realisation():
    te = TriadErrors(noise_density=[1e-3, 2e-3, 3e-3], bias_instability=GaussMarkov(1e-3, 1.0))
    _, tr = apply_errors(static(2000, 100.0), ImuErrorModel(gyro=te), rng=5, return_truth=True, common_axis_noise=True)
    w = tr.gyro.white_noise
    np.testing.assert_allclose(w[:, 1], 2 * w[:, 0], rtol=1e-12)
    np.testing.assert_allclose(w[:, 2], 3 * w[:, 0], rtol=1e-12)
    np.testing.assert_allclose(tr.gyro.bias_instability[:, 2], tr.gyro.bias_instability[:, 0], rtol=1e-12)


def test_all_terms_allan_variance_matches_model_oracle():
    # white + GM + random walk + ramp on one axis: the simulated Allan variance
    # follows TriadErrors.allan_variance (the sum of the closed forms); the
    # tolerance uses the least favourable power law (random-walk FM, alpha = -2).
    fs, n = 50.0, 1_000_000
    te = TriadErrors(
        noise_density=[2e-3, 0, 0],
        bias_instability=GaussMarkov([1e-3, 0, 0], 2.0),
        random_walk=[2e-5, 0, 0],
        rate_ramp=[1e-8, 0, 0],
    )
    y = apply_errors(static(n, fs), ImuErrorModel(gyro=te), rng=31).gyro[:, 0]
    for m in (5, 50, 500):
        expected = te.allan_variance([m / fs])[0, 0]
        tol = 4.0 * rel_sigma(-2, m, n)
        assert oavar(y, fs, m) == pytest.approx(expected, rel=tol)
