"""Stochastic error identification: Allan family, noise-term fitting, PSD,
AR / Gauss-Markov models, wavelet denoising."""

from imunav.noise.allan import KINDS, AllanResult, allan_deviation, allan_variance, tau_grid
from imunav.noise.fit import NoiseFit, SlopeReadout, avar_model, fit_noise, slope_readout, write_kalibr_yaml
from imunav.noise.psd import PsdFit, PsdResult, compare_psd_allan, fit_psd, frequency_average, log_average, psd

__all__ = [
    "KINDS", "AllanResult", "allan_deviation", "allan_variance", "tau_grid",
    "NoiseFit", "SlopeReadout", "avar_model", "fit_noise", "slope_readout", "write_kalibr_yaml",
    "PsdFit", "PsdResult", "compare_psd_allan", "fit_psd", "frequency_average", "log_average", "psd",
]
