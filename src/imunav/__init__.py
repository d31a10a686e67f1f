"""imunav: inertial sensors end to end.

Simulate, characterize and calibrate IMUs and magnetometers, and estimate
attitude and navigation with Kalman-filter families.  Conventions (SI units,
NED / FRD frames, Hamilton scalar-first quaternions body->nav, ZYX Euler) are
stated in ``docs/conventions.md``.
"""

from __future__ import annotations

__version__ = "0.1.0"

from imunav import errors, units  # noqa: E402,F401

__all__ = ["__version__", "errors", "units"]
