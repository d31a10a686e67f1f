"""Multi-position and six-position static calibration."""

import numpy as np
import pytest
from builders import G, hundred_positions, thesis_truth

from imunav.calib import multiposition, multiposition_from_means, parameter_stderr, six_position, success_percentages
from imunav.errors import DegenerateGeometryError, InsufficientDataError, SaturationError


def _means(truth, u, rng=None, sa=0.0, sg=0.0):
    f = G * u
    a, g = truth.invert_arrays(f, np.zeros_like(f))
    if rng is not None:
        a = a + rng.normal(scale=sa, size=a.shape)
        g = g + rng.normal(scale=sg, size=g.shape)
    return f, a, g


def test_hundred_positions_noise_free_exact():
    truth = thesis_truth()
    f, a, g = _means(truth, hundred_positions())
    r = multiposition_from_means(f, a, g)
    c = r.calibration
    np.testing.assert_allclose(c.accel_matrix, truth.accel_matrix, rtol=0, atol=1e-12)
    np.testing.assert_allclose(c.accel_bias, truth.accel_bias, rtol=1e-12)
    np.testing.assert_allclose(c.gyro_bias, truth.gyro_bias, rtol=1e-12)
    np.testing.assert_allclose(c.g_sensitivity, truth.g_sensitivity, rtol=1e-10, atol=1e-15)
    assert r.condition["accel"] < 10
    assert np.max(np.abs(r.residuals["accel"])) < 1e-12


def test_uncertainty_covers_truth_at_3_sigma():
    """Seeded Monte Carlo on per-position means: 3σ coverage ≥ 95 % for every parameter."""
    truth = thesis_truth()
    u = hundred_positions()
    rng = np.random.default_rng(7)
    from imunav.calib import calibration_parameters

    pt = calibration_parameters(truth)
    inside = {k: 0 for k in pt}
    n = 200
    for _ in range(n):
        f, a, g = _means(truth, u, rng, sa=6.7e-4 * G, sg=6.7e-3 * np.pi / 180)
        r = multiposition_from_means(f, a, g)
        pe = calibration_parameters(r.calibration)
        se = parameter_stderr(r.stderr)
        for k in ("accel_S", "accel_B", "accel_M", "gyro_B", "gyro_BG"):
            inside[k] += np.abs(pe[k] - pt[k]) <= 3 * se[k]
    for k in ("accel_S", "accel_B", "accel_M", "gyro_B", "gyro_BG"):
        assert np.all(inside[k] / n >= 0.95), (k, inside[k] / n)


def test_six_position_exact_without_misalignment_and_equal_to_lsq():
    truth = thesis_truth()
    u = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    f, a, g = _means(truth, u)
    r = six_position(a, g, gravity=G)
    # closed form is exact with misalignment too (noise-free), and equals the LS fit
    np.testing.assert_allclose(r.calibration.accel_matrix, truth.accel_matrix, atol=1e-13)
    np.testing.assert_allclose(r.calibration.accel_bias, truth.accel_bias, rtol=1e-13)
    # gyro bias from six poses absorbs nothing of G (opposite poses cancel)
    np.testing.assert_allclose(r.calibration.gyro_bias, truth.gyro_bias, rtol=1e-12)


def test_six_position_with_noise_close_to_multiposition(rng):
    truth = thesis_truth()
    u = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    f, a, g = _means(truth, u, rng, sa=1e-4, sg=0)
    six = six_position(a, None, gravity=G).calibration
    lsq = multiposition_from_means(f, a).calibration
    # same T (orthogonal design), biases differ only by noise
    np.testing.assert_allclose(six.accel_matrix, lsq.accel_matrix, atol=1e-14)
    assert np.all(np.abs(six.accel_bias - lsq.accel_bias) < 5e-4)


def test_time_series_with_transitions_and_hints(rng):
    """Static segments found from the data; transitions (tumbling motion) excluded."""
    truth = thesis_truth()
    u = hundred_positions()[::4]  # 25 positions
    fs, dwell, trans = 50.0, 6.0, 2.0
    f_list, windows = [], []
    t0 = 0.0
    for k in range(len(u)):
        n = int(dwell * fs)
        f_list.append(np.tile(G * u[k], (n, 1)))
        windows.append((t0, t0 + dwell))
        t0 += dwell
        if k < len(u) - 1:
            m = int(trans * fs)
            s = np.linspace(0, 1, m)[:, None]
            v = (1 - s) * u[k] + s * u[k + 1] + 0.3 * np.sin(np.pi * s) * rng.normal(size=3)
            f_list.append(G * v / np.linalg.norm(v, axis=1)[:, None])
            t0 += trans
    fb = np.vstack(f_list)
    a, g = truth.invert_arrays(fb, np.zeros_like(fb))
    a += rng.normal(scale=0.01, size=a.shape)
    g += rng.normal(scale=1e-3, size=g.shape)

    class Rec:
        t = np.arange(len(a)) / fs
        accel = a
        gyro = g

    r = multiposition(Rec, u, windows=np.array(windows), gravity=G)
    s = success_percentages(r.calibration.with_(gyro_matrix=truth.gyro_matrix), truth)
    assert s["accel_mean"] > 99.0
    # without hints the number of segments must match
    r2 = multiposition(Rec, u, gravity=G)
    np.testing.assert_allclose(r2.calibration.accel_matrix, r.calibration.accel_matrix, atol=2e-3)
    with pytest.raises(InsufficientDataError, match="found 25 static segments but 24"):
        multiposition(Rec, u[:-1], gravity=G)
    with pytest.raises(SaturationError, match="full-scale"):
        multiposition(Rec, u, windows=np.array(windows), gravity=G, full_scale=(12.0, None))


def test_refusals():
    truth = thesis_truth()
    u = np.array([[0, 0, -1.0]] * 10)  # one pose repeated: nothing but z excited
    f, a, g = _means(truth, u)
    with pytest.raises(DegenerateGeometryError, match="both signs"):
        multiposition_from_means(f, a, g)
    u4 = hundred_positions()[:4]
    f, a, g = _means(truth, u4)
    with pytest.raises(InsufficientDataError, match="4 positions/steps for 4 unknowns"):
        multiposition_from_means(f, a)


def test_six_position_refuses_reversed_poses_and_bad_gravity():
    """Poses in the wrong order or with negative gravity used to return T = -I silently (issue 16)."""
    from imunav.errors import DegenerateGeometryError, InvalidInputError

    truth = thesis_truth()
    u = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    _, a, g = _means(truth, u)
    swapped = a[[1, 0, 3, 2, 5, 4]]  # each axis' down pose given as its up pose
    with pytest.raises(DegenerateGeometryError, match="order"):
        six_position(swapped, g, gravity=G)
    with pytest.raises(DegenerateGeometryError, match="x axis"):
        six_position(a[[1, 0, 2, 3, 4, 5]], g, gravity=G)
    with pytest.raises(InvalidInputError, match="gravity"):
        six_position(a, g, gravity=-G)
