"""Stochastic error identification: Allan family, noise-term fitting, PSD,
AR / Gauss-Markov models, wavelet denoising."""

from imunav.noise.allan import KINDS, AllanResult, allan_deviation, allan_variance, tau_grid

__all__ = ["KINDS", "AllanResult", "allan_deviation", "allan_variance", "tau_grid"]
