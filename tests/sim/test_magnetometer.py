"""Virtual magnetometer: h = S C_nb^T h_ned + b + n."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from imunav.errors import DegenerateGeometryError, InvalidInputError, NonFiniteError, ShapeError
from imunav.rotation import dcm_from_quat, quat_from_euler
from imunav.sim.magnetometer import MagnetometerModel, simulate_magnetometer

FIELD = np.array([20.0, -1.5, 45.0])  # uT, NED (mid-latitude)


def attitudes(n: int, seed: int = 0) -> np.ndarray:
    r = np.random.default_rng(seed)
    eul = np.column_stack([r.uniform(-np.pi, np.pi, n), r.uniform(-1.5, 1.5, n), r.uniform(-np.pi, np.pi, n)])
    return quat_from_euler(eul)


def model() -> MagnetometerModel:
    s = np.array([[1.1, 0.05, -0.02], [0.05, 0.9, 0.03], [-0.02, 0.03, 1.05]])
    return MagnetometerModel(hard_iron=[12.0, -7.0, 30.0], soft_iron=s)


def test_noise_free_model_and_calibration_inverse():
    q = attitudes(500)
    m = model()
    h, hb = simulate_magnetometer(q, FIELD, m, rng=0, return_truth=True)
    c = dcm_from_quat(q)
    hb_ref = np.einsum("nji,j->ni", c, FIELD)  # C_nb^T h_ned
    np.testing.assert_allclose(hb, hb_ref, atol=1e-12)
    np.testing.assert_allclose(h, hb_ref @ m.soft_iron.T + m.hard_iron, atol=1e-12)
    # calibration recovers A = S^-1 and b: |A (h - b)| = |h_ned| exactly
    cal = (h - m.hard_iron) @ m.correction.T
    np.testing.assert_allclose(np.linalg.norm(cal, axis=1), np.linalg.norm(FIELD), rtol=1e-12)
    np.testing.assert_allclose(cal, hb_ref, atol=1e-12)


def test_noise_std_independence_and_seed():
    n = 100_000
    q = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    m = MagnetometerModel(noise=[0.1, 0.2, 0.3])
    h = simulate_magnetometer(SimpleNamespace(q_nb=q), FIELD, m, rng=3)
    e = h - FIELD
    np.testing.assert_allclose(e.std(axis=0), [0.1, 0.2, 0.3], rtol=0.03)  # sampling error 0.22 %
    c = np.corrcoef(e.T)
    assert np.max(np.abs(c[~np.eye(3, dtype=bool)])) < 4.5 / math.sqrt(n)
    np.testing.assert_array_equal(h, simulate_magnetometer(q, FIELD, m, rng=3))
    assert not np.array_equal(h, simulate_magnetometer(q, FIELD, m, rng=4))


def test_time_varying_field_and_single_attitude():
    q = attitudes(10)
    f = np.tile(FIELD, (10, 1)) * np.linspace(1, 2, 10)[:, None]
    h = simulate_magnetometer(q, f, MagnetometerModel())
    np.testing.assert_allclose(np.linalg.norm(h, axis=1), np.linalg.norm(f, axis=1), rtol=1e-12)
    assert simulate_magnetometer(np.array([1.0, 0, 0, 0]), FIELD, MagnetometerModel()).shape == (1, 3)


def test_bad_input():
    q = attitudes(5)
    with pytest.raises(ShapeError, match="q_nb.*\\(N, 4\\)"):
        simulate_magnetometer(np.zeros((5, 3)), FIELD, MagnetometerModel())
    with pytest.raises(ShapeError, match="field_ned"):
        simulate_magnetometer(q, FIELD[:2], MagnetometerModel())
    with pytest.raises(NonFiniteError, match="finite"):
        simulate_magnetometer(q, [np.nan, 0, 0], MagnetometerModel())
    with pytest.raises(InvalidInputError, match="MagnetometerModel"):
        simulate_magnetometer(q, FIELD, {"noise": 1})
    with pytest.raises(DegenerateGeometryError, match="singular"):
        MagnetometerModel(soft_iron=np.diag([1.0, 1.0, 0.0]))
    with pytest.raises(InvalidInputError, match="noise.*>= 0"):
        MagnetometerModel(noise=-0.1)
    with pytest.raises(ShapeError, match="hard_iron"):
        MagnetometerModel(hard_iron=[1.0, 2.0])
    m = model()
    assert MagnetometerModel.from_dict(m.to_dict()).to_dict() == m.to_dict()
