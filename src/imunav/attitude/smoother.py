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
    params : MekfParams
        Tuning of the forward MEKF; default :data:`imunav.attitude.adaptive.ADAPTIVE_DEFAULTS`.
    """

    params: MekfConfig = field(default_factory=lambda: ADAPTIVE_DEFAULTS)

    name = "smoother"

    def run(self, data: ImuData, *, q0: ArrayLike | None = None, bias0: ArrayLike | None = None,
            use_mag: bool | None = None) -> AttitudeResult:
        """Forward MEKF pass, then the backward RTS pass (Rauch, Tung & Striebel 1965; module docstring).

        Parameters
        ----------
        data : ImuData
            The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
        q0 : array_like, shape (4,), optional
            Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
            / magnetometer sample).
        bias0 : array_like, shape (3,), optional
            Initial gyro-bias estimate, rad/s (default zero).
        use_mag : bool, optional
            Use the magnetometer (9D); default: when the recording has one.

        Returns
        -------
        AttitudeResult
            Smoothed ``q_nb``, gyro bias (rad/s) and covariance diagonal at every sample, with the forward
            filter's flags.

        Raises
        ------
        InvalidInputError
            If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
            rate exceeds 1e4 rad/s.
        """
        f = MEKF(self.params)
        t, g, dt, um, q_init, b0, P0, out = f._run(data, q0, bias0, use_mag, True)
        qf, bf, _, fl, _, _, Pu, Pp, Ph = out
        qs, bs, pd = _k.rts_smooth(qf, bf, Pu, Pp, Ph, g, dt, P0, q_init, b0)
        flags = {k: (fl & v) > 0 for k, v in FLAG_NAMES.items()}
        return AttitudeResult(t=t, q_nb=qs, bias=bs, cov_diag=pd, flags=flags, name=self.name,
                              params={**{f_.name: getattr(self.params, f_.name) for f_ in fields(self.params)},
                                      "use_mag": um})
