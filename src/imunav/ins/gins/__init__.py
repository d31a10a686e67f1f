"""Loosely coupled GNSS/INS: configuration, filter, aids, smoother, alignment, outage test, truth and figures.

Modules: :mod:`~imunav.ins.gins.config` (:class:`GinsConfig`), :mod:`~imunav.ins.gins.filter`
(:class:`GinsFilter`), :mod:`~imunav.ins.gins.result` (:class:`GinsResult`, :class:`SmoothedTrack`,
:class:`AidRecord`), :mod:`~imunav.ins.gins.aids` (one measurement model per aid), :mod:`~imunav.ins.gins.kernels`
(the numba loop), :mod:`~imunav.ins.gins.layout` (the kernel's named layouts), :mod:`~imunav.ins.gins.smoother`
(RTS).
"""

from imunav.ins.gins.config import STATE_NAMES, GinsConfig
from imunav.ins.gins.filter import GinsFilter
from imunav.ins.gins.result import AidRecord, GinsResult, SmoothedTrack

__all__ = ["AidRecord", "GinsConfig", "GinsFilter", "GinsResult", "SmoothedTrack", "STATE_NAMES"]
