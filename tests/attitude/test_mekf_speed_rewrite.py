"""The allocation-free MEKF kernel (issue 34) against the frozen kernel it replaced.

``_mekf_frozen.py`` is the kernel as it was before the rewrite (generic 6x6 matrix products, allocations in the
loop).  The rewrite computes the same equations in another order (closed-form covariance reset and consider
heading update, fused multiply-adds), so the outputs agree to rounding, not bit for bit: the bounds below are a
few hundred times the differences measured when this was written (quaternion 4e-14, bias 2e-14, covariance
diagonal 5e-12 relative on BROAD trial 05), far below any effect of the algorithm, and every flag is identical.
The recording exercises every branch: rest (zero-rate updates), a magnetic disturbance, an acceleration bump,
rotation; each configuration switches a different set of the adaptive parts on.
"""

from dataclasses import replace

import numpy as np
import pytest
from _mekf_frozen import mekf_run_frozen
from builders import disturbed_imu
from shared_data import data_path

from imunav.attitude import _kernels as _k
from imunav.attitude._base import initial_q, prepare
from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS, AdaptiveMEKF
from imunav.attitude.mekf import MEKF, MekfConfig
from imunav.attitude.smoother import Smoother
from imunav.timeseries import ImuData

# one worker runs the module: the frozen kernel (a test-only numba kernel, about 15 s to compile) is compiled once,
# not by both workers at once
pytestmark = pytest.mark.xdist_group("frozen_mekf")

CONFIGS = {
    "mekf": MekfConfig(),
    "adaptive": ADAPTIVE_DEFAULTS,
    "adaptive_consider_bias": replace(ADAPTIVE_DEFAULTS, mag_bias=False, k_mag=1.0, mag_ref_time=2.0, k_accel=0.5,
                                      accel_reject_threshold=0.05, k_rate=0.01, k_gyro_rate=0.01),
    "plain_rest": MekfConfig(rest_gyro_threshold=0.05, rest_accel_threshold=0.3, mag_norm_threshold=0.1,
                             mag_dip_threshold=0.2, heading_noise_std=0.1),
}


def _recording():
    return disturbed_imu()[0]


def _compare(data, cfg, use_mag, store=False):
    t, g, a, m, dt, um = prepare(data, use_mag)
    p = cfg.vector()
    p[_k.P_USE_MAG] = 1.0 if um else 0.0
    q0 = initial_q(a, m, um, None)
    new = _k.mekf_run(q0, np.zeros(3), cfg.P0(), g, a, m, dt, p, store)
    old = mekf_run_frozen(q0, np.zeros(3), cfg.P0(), g, a, m, dt, p, store)
    np.testing.assert_allclose(new[0], old[0], rtol=0, atol=1e-11)  # q
    np.testing.assert_allclose(new[1], old[1], rtol=0, atol=1e-11)  # bias, rad/s
    np.testing.assert_allclose(new[2], old[2], rtol=1e-9, atol=0)  # covariance diagonal
    np.testing.assert_array_equal(new[3], old[3])  # flags
    np.testing.assert_allclose(new[4], old[4], rtol=1e-8, atol=1e-12)  # NIS
    np.testing.assert_array_equal(new[5], old[5])  # dof
    if store:
        for i in (6, 7, 8):  # P after update, P predicted, Φ
            np.testing.assert_allclose(new[i], old[i], rtol=1e-8, atol=1e-18)
    return new


@pytest.mark.parametrize("use_mag", [True, False], ids=["9D", "6D"])
@pytest.mark.parametrize("name", list(CONFIGS))
def test_fast_kernel_reproduces_the_frozen_kernel(name, use_mag):
    new = _compare(_recording(), CONFIGS[name], use_mag)
    flags = new[3]
    if name != "mekf":  # the branches the comparison covers were taken
        assert np.any(flags & 4), "no rest detected"
        if use_mag:
            assert np.any(flags & 2), "no field disturbance detected"


def test_stored_covariances_of_the_smoother_unchanged():
    _compare(_recording(), ADAPTIVE_DEFAULTS, True, store=True)


@pytest.mark.data
@pytest.mark.parametrize("name", ["mekf", "adaptive"])
def test_fast_kernel_on_broad_sample(name):
    z = np.load(data_path("vqf_sample", "imu_data.npz"))
    n = 6000
    data = ImuData(t=np.arange(n) / (2000 / 7), gyro=z["gyr"][:n].astype(float), accel=z["acc"][:n].astype(float),
                   mag=z["mag"][:n].astype(float))
    _compare(data, CONFIGS[name], True)


def test_step_run_and_run_many_agree():
    """The per-sample API, the whole-recording kernel and the threaded batch give the same attitude."""
    data = _recording()
    f = AdaptiveMEKF()
    r = f.run(data)
    g = AdaptiveMEKF()
    g.reset(initial_q(data.accel, data.mag, True, None))
    dt = np.diff(data.t, prepend=2 * data.t[0] - data.t[1])  # run()'s steps: dt[0] = t[1] - t[0]
    qs = [g.step(data.gyro[k], data.accel[k], data.mag[k], dt[k]) for k in range(data.n)]
    np.testing.assert_allclose(np.array(qs), r.q_nb, rtol=0, atol=1e-12)
    other = data.slice(0, 2000)
    many = f.run_many([data, other, data], workers=2)
    np.testing.assert_array_equal(many[0].q_nb, r.q_nb)
    np.testing.assert_array_equal(many[2].q_nb, r.q_nb)
    np.testing.assert_array_equal(many[1].q_nb, AdaptiveMEKF().run(other).q_nb)
    assert MEKF().run_many([other], workers=1)[0].name == "mekf"


def test_smoother_runs_on_the_stored_path():
    r = Smoother().run(_recording())
    assert np.all(np.isfinite(r.q_nb))
