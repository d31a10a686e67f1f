"""Stochastic error identification: Allan family, noise-term fitting, PSD,
AR / Gauss-Markov models, wavelet denoising, curve fits of the Allan curve.

Main entry points: :func:`require_static` (the gate: noise identification
needs a recording at rest), :func:`allan_deviation` -> :class:`AllanResult`,
:func:`fit_noise` -> :class:`NoiseFit`, :func:`psd` / :func:`fit_psd`,
:func:`fit_gauss_markov`, :func:`wavelet_denoise`; :class:`NoiseProfile` (the
sensor's N, B, K per axis that the filters' configurations are built from); figures in
:mod:`imunav.noise.plot`.
"""

from imunav.io.kalibr import write_kalibr_yaml  # re-export: the README's noise API names it here
from imunav.noise.allan import KINDS, AllanResult, allan_deviation, allan_variance, tau_grid
from imunav.noise.ar import GaussMarkovFit, autocorrelation, fit_gauss_markov, gm_discrete, yule_walker
from imunav.noise.curvefit import CurveFit, compare_curve_fits, fit_polynomial, fit_rational
from imunav.noise.fit import NoiseFit, SlopeReadout, avar_model, fit_noise, identifiability, slope_readout
from imunav.noise.profile import NoiseProfile, NoiseTerm, SensorNoise, read_noise_profile
from imunav.noise.psd import (
    PsdFit,
    PsdResult,
    compare_psd_allan,
    fit_psd,
    frequency_average,
    log_average,
    psd,
    psd_readout,
)
from imunav.noise.static import StaticCheck, check_static, require_static
from imunav.noise.wavelet import compare_hybrid, wavelet_denoise

__all__ = [
    "KINDS", "AllanResult", "allan_deviation", "allan_variance", "tau_grid",
    "NoiseFit", "SlopeReadout", "avar_model", "fit_noise", "identifiability", "slope_readout", "write_kalibr_yaml",
    "PsdFit", "PsdResult", "compare_psd_allan", "fit_psd", "frequency_average", "log_average", "psd", "psd_readout",
    "GaussMarkovFit", "autocorrelation", "fit_gauss_markov", "gm_discrete", "yule_walker",
    "CurveFit", "compare_curve_fits", "fit_polynomial", "fit_rational",
    "compare_hybrid", "wavelet_denoise",
    "StaticCheck", "check_static", "require_static",
    "NoiseProfile", "NoiseTerm", "SensorNoise", "read_noise_profile",
]
