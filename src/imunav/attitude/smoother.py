"""Offline forward-backward smoother (RTS on the MEKF error state).

The forward pass is the adaptive MEKF (:mod:`imunav.attitude.mekf`), storing
P⁺_k, P⁻_k and Φ_k; the backward pass is the Rauch-Tung-Striebel recursion
(Rauch, Tung, Striebel, AIAA J. 3(8), 1965) applied to the error state with
the nominal trajectory re-linearised at the filtered estimate:

    C_k = P⁺_k Φ_{k+1}ᵀ (P⁻_{k+1})⁻¹
    δx^s_k = C_k (x^s_{k+1} ⊟ x̂⁻_{k+1}),  x^s_k = x̂⁺_k ⊞ δx^s_k
    P^s_k = P⁺_k + C_k (P^s_{k+1} − P⁻_{k+1}) C_kᵀ

where x̂⁻_{k+1} is the filter's one-step prediction from x̂⁺_k and ⊞ / ⊟ are
the multiplicative attitude update / its inverse (rotation vector of
q̂⁻* ⊗ q^s) plus the additive bias.  Intervals where the magnetometer was
rejected get their heading from both sides, which is where the smoother gains
most over the real-time filter.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

from numpy.typing import ArrayLike

from imunav._docstrings import fill_doc
from imunav.attitude import _kernels as _k
from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS
from imunav.attitude.mekf import FLAG_NAMES, MEKF, MekfConfig
from imunav.attitude.result import AttitudeResult
from imunav.timeseries import ImuData

__all__ = ["Smoother"]


@dataclass
class Smoother:
    """RTS smoother over the adaptive MEKF (offline only: no step API).

    Attributes
    ----------
    config : MekfConfig
        Tuning of the forward MEKF; default :data:`imunav.attitude.adaptive.ADAPTIVE_DEFAULTS`.
    """

    config: MekfConfig = field(default_factory=lambda: ADAPTIVE_DEFAULTS)

    name = "smoother"

    @fill_doc
    def run(self, data: ImuData, *, q0: ArrayLike | None = None, bias0: ArrayLike | None = None,
            use_mag: bool | None = None) -> AttitudeResult:
        """Forward MEKF pass, then the backward RTS pass (Rauch, Tung & Striebel 1965; module docstring).

        %(att_run_bias_mag)s

        Returns
        -------
        AttitudeResult
            Smoothed ``q_nb``, gyro bias (rad/s) and covariance diagonal at every sample, with the forward
            filter's flags.

        %(att_run_raises)s
        """
        f = MEKF(self.config)
        t, g, dt, um, q_init, b0, P0, out = f._run(data, q0, bias0, use_mag, True)
        qf, bf, _, fl, _, _, Pu, Pp, Ph = out
        qs, bs, pd = _k.rts_smooth(qf, bf, Pu, Pp, Ph, g, dt, P0, q_init, b0)
        flags = {k: (fl & v) > 0 for k, v in FLAG_NAMES.items()}
        return AttitudeResult(t=t, q_nb=qs, bias=bs, cov_diag=pd, flags=flags, name=self.name,
                              params={**{f_.name: getattr(self.config, f_.name) for f_ in fields(self.config)},
                                      "use_mag": um})
