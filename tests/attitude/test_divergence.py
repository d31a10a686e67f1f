"""Attitude filters given absurd noise refuse their overflow instead of returning NaN quaternions (issue 36).

A noise density of 1e300 (a hand-edited profile, a unit mix-up) made the Kalman filters' arithmetic overflow: the
command line said so, but ``MEKF(...).run`` from Python returned NaN quaternions without a word.  Now every public
entry (the filter classes, ``imunav.estimate_attitude``) raises :class:`imunav.errors.ConvergenceError` naming the
filter, the first sample that is not finite and the parameter of largest magnitude; configurations whose numbers
overflow before the run (an initial σ whose square is inf, a Mahony gain beyond any gyro's rate) are refused when
built.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import imunav
from imunav.attitude import MEKF, UKF, AdaptiveMEKF, Mahony, Smoother
from imunav.attitude.benchmark import make_filter
from imunav.attitude.mekf import MekfConfig
from imunav.errors import ConfigError, ConvergenceError, InvalidInputError
from imunav.timeseries import ImuData


def _rec(n: int = 400, fs: float = 100.0) -> ImuData:
    """A sensor turning slowly about a tilted axis, with gravity and a field: finite and ordinary."""
    t = np.arange(n) / fs
    gyro = np.tile([0.05, -0.02, 0.3], (n, 1))
    accel = np.tile([0.3, -0.2, -9.8], (n, 1))
    mag = np.tile([0.2, 0.05, 0.4], (n, 1))
    return ImuData(t=t, gyro=gyro, accel=accel, mag=mag)


@pytest.mark.parametrize("name", ["mekf", "adaptive", "smoother", "ukf"])
@pytest.mark.parametrize("use_mag", [True, False], ids=["9D", "6D"])
def test_overflowing_noise_raises_with_what_where_and_how(name, use_mag):
    f = make_filter(name, {"gyro_noise_density": 1e300})
    assert isinstance(f, (MEKF, AdaptiveMEKF, Smoother, UKF))
    with pytest.raises(ConvergenceError) as e:
        f.run(_rec(), use_mag=use_mag)
    msg = str(e.value)
    m = re.match(rf"{f.name} diverged: its (attitude|covariance) is not finite from sample (\d+) \(t = ", msg)
    assert m, msg
    assert int(m.group(2)) < 400
    assert "largest: gyro_noise_density = 1e+300" in msg and "SI units" in msg, msg


def test_the_same_filter_with_a_sensors_noise_runs_finite():
    """The check refuses only overflow: the same filters with ordinary (and large but finite-squared) noise run."""
    for kw in ({}, {"gyro_noise_density": 1e100}):
        r = MEKF(MekfConfig(**kw)).run(_rec())
        assert np.isfinite(r.q_nb).all() and np.isfinite(r.cov_diag).all()
    assert np.isfinite(AdaptiveMEKF().run(_rec()).q_nb).all()


def test_estimate_attitude_raises_too():
    with pytest.raises(ConvergenceError, match=r"^adaptive diverged: .*largest: gyro_bias_random_walk = 1e\+300"):
        imunav.estimate_attitude(_rec(), "adaptive", gyro_bias_random_walk=1e300)


def test_overflowing_initial_sigma_is_refused_when_built():
    for name in ("init_att_std", "init_gyro_bias_std"):
        with pytest.raises(ConfigError, match=rf"^MekfConfig\.{name} = 1e\+200: its square, the initial variance, "
                                              r"overflows; give a standard deviation in SI"):
            MekfConfig(**{name: 1e200})
    assert MekfConfig(init_att_std=1e100).P0()[0, 0] == 1e200


@pytest.mark.parametrize("gain", ["kp", "ki"])
def test_mahony_gain_beyond_any_gyro_is_refused(gain):
    """Mahony(kp=1e300) ended in a ZeroDivisionError inside the kernel; 1e4 (the bound) still runs finite."""
    with pytest.raises(InvalidInputError, match=rf"^Mahony\.{gain} must be <= 10000 "):
        Mahony(**{gain: 1e300})
    assert np.isfinite(Mahony(**{gain: 1e4}).run(_rec()).q_nb).all()
