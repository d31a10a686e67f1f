"""GNSS/INS aid models: every model's Jacobian rows are the central-difference derivative of its own innovation
under the filter's own error injection, and the kernel's named layouts hold together."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.earth import OMEGA_E
from imunav.ins.gins import GinsConfig, aids
from imunav.ins.gins.filter import kernel_setup
from imunav.ins.gins.kernels import _inject
from imunav.ins.gins.layout import CTX, LAY, N_CTX, N_LAY, N_NOM, NOM, STATE_BLOCKS
from imunav.rotation import dcm_from_quat, quat_normalize

#: central-difference step per state block (SI): large enough that rounding of the innovation (a position of
#: ~6e6 m in radians: ~1e-9 m) stays far below the Jacobian's entries, small enough that the curvature is negligible
EPS = {"pos": 1e-2, "vel": 1e-3, "att": 1e-4, "gyro_bias": 1e-6, "accel_bias": 1e-4, "gyro_scale": 1e-4,
       "accel_scale": 1e-4, "odo_scale": 1e-4, "mount": 1e-4, "odo_lever": 1e-3, "gnss_delay": 1e-4, "gnss_bias": 1e-2,
       "odo_turn": 1e-4, "side_slip": 1e-4}


BASELINE = (1.2, -0.4, 0.15)
VEHICLE_BLOCKS = {"mounting_std": 0.01, "odo_lever_arm_std": 0.1, "gnss_delay_std": 0.05, "gnss_bias_std": 0.5,
                  "side_slip_std": 0.1}


def _state(rng):
    xs = np.zeros(N_NOM)
    xs[NOM.lla:NOM.lla + 3] = (0.53, 1.99, 35.0)
    xs[NOM.vel:NOM.vel + 3] = rng.normal(0, 5, 3)
    xs[NOM.q:NOM.q + 4] = quat_normalize(rng.normal(size=4))
    xs[NOM.gyro_bias:NOM.gyro_bias + 3] = rng.normal(0, 1e-4, 3)
    xs[NOM.accel_bias:NOM.accel_bias + 3] = rng.normal(0, 1e-2, 3)
    xs[NOM.gyro_scale:NOM.gyro_scale + 3] = rng.normal(0, 1e-3, 3)
    xs[NOM.accel_scale:NOM.accel_scale + 3] = rng.normal(0, 1e-3, 3)
    xs[NOM.odo_scale] = 0.02
    xs[NOM.q_vb:NOM.q_vb + 4] = quat_normalize(rng.normal(size=4))
    xs[NOM.odo_lever:NOM.odo_lever + 3] = (-0.5, 0.6, 0.4)
    xs[NOM.gnss_delay] = 0.12
    xs[NOM.gnss_bias:NOM.gnss_bias + 3] = (0.3, -0.2, 0.5)
    xs[NOM.gnss_r_scale] = 1.3  # the adaptive factor on the reported covariance
    xs[NOM.odo_turn] = 0.15  # the odometer's over-reading in turns, s/rad
    xs[NOM.side_slip] = 0.08  # the side slip per m/s² of lateral acceleration, rad/(m/s²)
    xs[NOM.odo_r_scale] = 2.0  # the adaptive factors on the odometer's and the NHC's covariance
    xs[NOM.nhc_r_scale] = 0.7
    return xs


def _context(xs, w_raw):
    """The update context as the models define it: compensated rates ``(ω̃ − b̂) / (1 + ŝ)`` of the state."""
    ctx = np.zeros(N_CTX)
    w = (w_raw - xs[NOM.gyro_bias:NOM.gyro_bias + 3]) / (1 + xs[NOM.gyro_scale:NOM.gyro_scale + 3])
    ctx[CTX.w_mean:CTX.w_mean + 3] = w
    ctx[CTX.w_sample:CTX.w_sample + 3] = w
    ctx[CTX.w_raw:CTX.w_raw + 3] = w_raw
    ctx[CTX.dt_raw] = 0.2
    return ctx


def _measurement(name, rng, xs):
    """A measurement near the model's prediction (the innovation is small, as in a converged filter)."""
    if name == "gnss_position":
        return xs[NOM.lla:NOM.lla + 3] + (1e-7, 1e-7, 0.3), np.diag([0.5, 0.5, 1.0])
    if name == "gnss_velocity":
        return xs[NOM.vel:NOM.vel + 3] + 0.05, np.diag([0.01, 0.01, 0.02])
    if name == "odometer":
        return np.array([np.linalg.norm(xs[NOM.vel:NOM.vel + 3]), 0.0025]), np.zeros((3, 3))
    if name == "baro":
        return np.array([xs[NOM.lla + 2] + 1.0]), np.zeros((3, 3))
    if name == "mag_heading":  # the field of the model's declination (0.1 rad) and a 60° inclination, in body axes
        inc = np.radians(60.0)
        mn = 48.0 * np.array([np.cos(inc) * np.cos(0.1), np.cos(inc) * np.sin(0.1), np.sin(inc)])
        return dcm_from_quat(xs[NOM.q:NOM.q + 4]).T @ mn, np.zeros((3, 3))
    if name == "dual_antenna":  # heading and pitch of the configured baseline at the state's attitude
        bn = dcm_from_quat(xs[NOM.q:NOM.q + 4]) @ np.array(BASELINE)
        z = np.array([np.arctan2(bn[1], bn[0]), np.arctan2(-bn[2], np.hypot(bn[0], bn[1]))])
        return z, np.diag([1e-5, 4e-5, 0.0])
    return np.zeros(1), np.zeros((3, 3))  # placeholders of NHC, ZUPT, ZARU


def _rows(kind, xs, ctx, z, r, prm, lay):
    m = int(aids.ROWS[kind])
    nx = int(lay[LAY.nx])
    H, R, nu = np.zeros((m + 2, nx)), np.zeros((m + 2, m + 2)), np.zeros(m + 2)
    aids.evaluate(kind, xs, ctx, z, r, prm[lay[N_LAY + kind]:], lay, H, R, nu, 1)  # at row 1: the offset is honoured
    assert not H[0].any() and not H[m + 1].any() and nu[0] == 0 and nu[m + 1] == 0
    return nu[1:m + 1], H[1:m + 1], R[1:m + 1, 1:m + 1]


@pytest.mark.parametrize("scale_factors", [True, False])
@pytest.mark.parametrize("name", aids.AID_NAMES)
def test_every_aid_jacobian_is_the_derivative_of_its_innovation(name, scale_factors, rng):
    """``H[:, j] = −∂ν/∂δx_j`` with ``x̂ ⊕ δx`` the filter's own injection (errors are true − estimate); a sign or
    factor error in any column errs by the size of that column, far above the tolerance.  Every state block
    present (21 states and the vehicle blocks: mounting, wheel lever arm, GNSS latency, the fixes' correlated
    error), or 15 + odometer scale."""
    cfg = GinsConfig(gyro_noise_density=1e-3, accel_noise_density=1e-2, gyro_bias_std=1e-4, accel_bias_std=1e-3, nhc_noise_std=0.1,
                     lever_arm=(0.4, -0.3, -1.2), odo_lever_arm=(-0.5, 0.6, 0.4), scale_factors=scale_factors,
                     declination=0.1, dual_antenna_baseline=BASELINE, level_noise_std=0.03,
                     **(VEHICLE_BLOCKS if scale_factors else {}))
    prm, lay, _ = kernel_setup(cfg, 100.0, True)
    kind = getattr(aids.AID, name)
    xs = _state(rng)
    if not scale_factors:  # a 15-state filter treats the scale factors as zero
        xs[NOM.gyro_scale:NOM.accel_scale + 3] = 0.0
    assert (lay[LAY.mount] >= 0) == scale_factors == (lay[LAY.side_slip] >= 0)
    w_raw = rng.normal(0, 0.3, 3)
    z, r = _measurement(name, rng, xs)
    nu0, H, R = _rows(kind, xs, _context(xs, w_raw), z, r, prm, lay)
    assert np.all(np.isfinite(nu0)) and np.all(np.linalg.eigvalsh(R) > 0)
    nx = int(lay[LAY.nx])
    J = np.zeros_like(H)
    for block, size in STATE_BLOCKS:
        i0 = lay[getattr(LAY, block)]
        if i0 < 0:
            continue
        for j in range(i0, i0 + size):
            nus = []
            for sgn in (1.0, -1.0):
                x = xs.copy()
                dx = np.zeros(nx)
                dx[j] = sgn * EPS[block]
                _inject(dx, x, lay, np.zeros(nx))
                nus.append(_rows(kind, x, _context(x, w_raw), z, r, prm, lay)[0])
            J[:, j] = -(nus[0] - nus[1]) / (2 * EPS[block])
    # What the first-order models neglect: products of the scale-factor estimates with the errors (relative
    # |ŝ| ~ 1e-3, e.g. ∂ω/∂δb_g = −1/(1 + ŝ) taken as −1) and, for the antenna velocity, the Earth rate through
    # the attitude (Ω |l| ~ 1e-4 m/s per rad); a sign or factor error errs by the size of the entry itself.
    s_max = np.abs(xs[NOM.gyro_scale:NOM.accel_scale + 3]).max() if scale_factors else 0.0
    neglected = {"gnss_velocity": 2 * OMEGA_E * np.linalg.norm(cfg.lever_arm)}.get(name, 0.0)
    np.testing.assert_allclose(H, J, rtol=2 * s_max + 1e-4, atol=neglected + 1e-6 * np.abs(H).max())
    assert np.all(np.abs(H).max(axis=1) > 0)
    # the adaptive factors scale the covariance of their own aid only (GinsConfig.wheel_adaptive, gnss_adaptive)
    nominal = {"odometer": lambda: np.diag([z[1]]), "nhc": lambda: np.eye(2) * cfg.nhc_noise_std**2,
               "gnss_position": lambda: r}
    if name in nominal:
        factor = {"odometer": NOM.odo_r_scale, "nhc": NOM.nhc_r_scale, "gnss_position": NOM.gnss_r_scale}[name]
        np.testing.assert_allclose(R, xs[factor] * nominal[name](), rtol=1e-12)


def test_kernel_layouts_are_contiguous_and_follow_their_tuples():
    from imunav.ins.gins import layout

    for lay, n in ((layout.NOM, layout.N_NOM), (layout.PRM, layout.N_PRM), (layout.CTX, layout.N_CTX),
                   (layout.LAY, layout.N_LAY)):
        starts = list(lay)
        assert starts == sorted(starts) and starts[0] == 0 and starts[-1] < n, type(lay).__name__
    assert layout.LAY._fields[:len(STATE_BLOCKS)] == tuple(b for b, _ in STATE_BLOCKS)
    # the 15 / 21 / 22-state layouts: blocks back to back in STATE_BLOCKS order, absent ones -1
    # (with the odometer: its scale and its over-reading in turns)
    for scale, odo, nx in ((False, False, 15), (True, False, 21), (True, True, 23), (False, True, 17)):
        cfg = GinsConfig(gyro_noise_density=1e-3, accel_noise_density=1e-2, gyro_bias_std=1e-4, accel_bias_std=1e-3, scale_factors=scale)
        prm, lay, P0 = kernel_setup(cfg, 100.0, odo)
        assert lay[LAY.nx] == nx == P0.shape[0] and np.array_equal(P0, np.diag(np.diag(P0)))
        i = 0
        for block, size in STATE_BLOCKS:
            if lay[getattr(LAY, block)] >= 0:
                assert lay[getattr(LAY, block)] == i
                i += size
        assert i == nx
        # each aid's parameter block packs what its params() returns, at its offset
        for kind, model in enumerate(aids.MODELS):
            off = lay[N_LAY + kind]
            np.testing.assert_array_equal(prm[off:off + model.N_PARAMS], model.params(cfg))
    assert set(aids.TIMED) | {a for g in aids.SAMPLED for a in g} == set(aids.AID_NAMES)
    assert aids.N_AIDS + len(aids.SAMPLED) <= layout.MAX_SOURCES  # a rejection counter per update source
    assert max(len(g) for g in aids.SAMPLED) <= layout.MAX_GROUP
    # a constant plus a Gauss-Markov bias: the two Gauss-Markov blocks last, correlated with the whole biases
    cfg = GinsConfig(gyro_noise_density=1e-3, accel_noise_density=1e-2, gyro_bias_std=1e-4, accel_bias_std=1e-3,
                     init_gyro_bias_std=1e-2, init_accel_bias_std=1e-1, bias_model="constant_and_gauss_markov")
    _, lay, P0 = kernel_setup(cfg, 100.0, True)
    assert lay[LAY.nx] == 29 and lay[LAY.gyro_bias_gm] == 22 and lay[LAY.accel_bias_gm] == 25
    for whole, part, gm, init in ((LAY.gyro_bias, LAY.gyro_bias_gm, 1e-4, 1e-2),
                                   (LAY.accel_bias, LAY.accel_bias_gm, 1e-3, 1e-1)):
        i, k = lay[whole], lay[part]
        np.testing.assert_allclose(np.diag(P0)[i:i + 3], init**2)
        np.testing.assert_allclose(np.diag(P0)[k:k + 3], gm**2)
        np.testing.assert_allclose(np.diag(P0[i:i + 3, k:k + 3]), gm**2)
    assert np.linalg.eigvalsh(P0).min() > 0
