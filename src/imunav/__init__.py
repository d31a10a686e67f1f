"""imunav: inertial sensors end to end.

Simulate, characterize and calibrate IMUs and magnetometers, and estimate
attitude and navigation with Kalman-filter families.  Conventions (SI units,
NED / FRD frames, Hamilton scalar-first quaternions body->nav, ZYX Euler) are
stated in ``docs/conventions.md``.

The entry points of a notebook are attributes of the package: ``imunav.read``, ``imunav.analyse_noise``,
``imunav.calibrate``, ``imunav.estimate_attitude`` and ``imunav.navigate`` (:mod:`imunav.notebook`; each result
has ``summary()`` and ``plot()``).  They load on first use, so that ``import imunav`` (and every command,
which imports the package first) stays light.
"""

from __future__ import annotations

__version__ = "0.1.0"

from imunav import errors, units  # noqa: E402,F401

#: the notebook entry points (:mod:`imunav.notebook`), loaded on first access by :func:`__getattr__`
NOTEBOOK = ("read", "analyse_noise", "calibrate", "estimate_attitude", "navigate")

__all__ = ["__version__", "errors", "units", *NOTEBOOK]


def __getattr__(name: str):
    """The notebook entry points on first access (PEP 562); the one function-level import of the package,
    allowed by ``tests/test_import_graph.py`` and ``docs/design.md`` (section 1) as the root's lazy re-export."""
    if name in NOTEBOOK:
        from imunav import notebook  # lazy re-export: the package root (layer 0) names the layer-4 entry points

        return getattr(notebook, name)
    raise AttributeError(f"module 'imunav' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *NOTEBOOK})
