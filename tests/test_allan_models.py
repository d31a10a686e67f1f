"""The closed-form Allan variances (imunav.allan_models) against 50-digit values,
and noise / sim sharing that one implementation."""

from __future__ import annotations

import numpy as np
import pytest

mpmath = pytest.importorskip("mpmath")

from imunav import allan_models as am  # noqa: E402 (after the importorskip)
from imunav.errors import InvalidInputError  # noqa: E402
from imunav.noise import avar_model  # noqa: E402
from imunav.noise.fit import avar_term  # noqa: E402
from imunav.sim import allan_variance_gauss_markov, allan_variance_ieee952  # noqa: E402


def _gm_unit_mp(tau: float, T: float) -> float:
    """(2T/tau) [1 - (3 - 4e^-u + e^-2u)/(2u)], u = tau/T, at 60 significant digits."""
    with mpmath.workdps(60):
        t, c = mpmath.mpf(tau), mpmath.mpf(T)
        u = t / c
        f = 1 - (3 - 4 * mpmath.exp(-u) + mpmath.exp(-2 * u)) / (2 * u)
        return float(2 * c / t * f)


U = np.logspace(-8, 3, 221)


@pytest.mark.parametrize("T", [1e-3, 1.0, 37.0, 1e4])
def test_gauss_markov_matches_50_digit_values(T):
    tau = U * T
    exact = np.array([_gm_unit_mp(t, T) for t in tau])
    for got in (avar_term("GM", tau, T), allan_variance_gauss_markov(tau, 1.0, T), am.gauss_markov_unit(tau, T)):
        rel = np.abs(got / exact - 1.0)
        assert rel.max() < 1e-10, (rel.max(), U[rel.argmax()])


def test_issue_value_and_series_switch():
    # u = 9e-4: exact bracket 2.69798e-7 (the old series u/3 - u^2/4 gave 3.0e-4)
    u = 9e-4
    assert am.gauss_markov_bracket(u) == pytest.approx(u**2 / 3 - u**3 / 4 + 7 * u**4 / 60, rel=1e-12)
    # both branches either side of the switch at u = 1/2 agree with the exact values
    for uu in (0.5 - 1e-12, 0.5, 0.5 + 1e-12):
        assert float(am.gauss_markov_unit(uu, 1.0)) == pytest.approx(_gm_unit_mp(uu, 1.0), rel=1e-13)


def test_noise_and_sim_share_one_implementation():
    tau = np.logspace(-3, 4, 50)
    q, n, b, k, r = 1e-4, 2e-3, 3e-5, 4e-6, 5e-8
    gm = [(1e-3, 0.7), (2e-4, 300.0)]
    ref = allan_variance_ieee952(tau, Q=q, N=n, B=b, K=k, R=r) + sum(
        allan_variance_gauss_markov(tau, s, t) for s, t in gm)
    np.testing.assert_allclose(avar_model(tau, Q=q, N=n, B=b, K=k, R=r, gm=gm), ref, rtol=1e-14)
    ieee = {"Q": 3 / tau**2, "N": 1 / tau, "B": np.full_like(tau, 2 * np.log(2) / np.pi), "K": tau / 3,
            "R": tau**2 / 2}
    for name, expected in ieee.items():
        np.testing.assert_allclose(avar_term(name, tau), expected, rtol=1e-15)
    with pytest.raises(InvalidInputError):
        avar_term("GM", tau, None)
    with pytest.raises(InvalidInputError):
        avar_term("X", tau)
    with pytest.raises(InvalidInputError):
        allan_variance_gauss_markov(tau, 1.0, -1.0)
