"""Exception types of imunav.

Every exception raised for bad input says *what* is wrong, *where* (row,
column, file, argument) and *how to fix it*.  All input errors derive from
:class:`InvalidInputError`, itself a :class:`ValueError`, so callers that
catch ``ValueError`` keep working.
"""

from __future__ import annotations

__all__ = [
    "ImunavError",
    "InvalidInputError",
    "ShapeError",
    "NonFiniteError",
    "TimeOrderError",
    "UnitError",
    "FileFormatError",
    "InsufficientDataError",
    "DegenerateGeometryError",
    "SaturationError",
    "ConvergenceError",
    "MissingDependencyError",
    "ConfigError",
    "ProvenanceError",
    "RunFolderError",
    "NotStaticError",
    "ImunavWarning",
]


class ImunavError(Exception):
    """Base class of every imunav exception."""


class InvalidInputError(ImunavError, ValueError):
    """An argument, array or file content is not acceptable."""


class ShapeError(InvalidInputError):
    """An array has the wrong number of dimensions or the wrong size."""


class NonFiniteError(InvalidInputError):
    """NaN or infinite values where finite ones are required."""


class TimeOrderError(InvalidInputError):
    """Time stamps are not strictly increasing (duplicates or going back)."""


class UnitError(InvalidInputError):
    """A unit string is unknown or does not fit the quantity."""


class FileFormatError(InvalidInputError):
    """A file is empty, truncated, or lacks the expected columns / datasets."""


class InsufficientDataError(InvalidInputError):
    """Too few samples, poses or intervals to estimate what was asked."""


class DegenerateGeometryError(InvalidInputError):
    """The data do not excite the model (planar coverage, collinear poses...)."""


class SaturationError(InvalidInputError):
    """Samples sit at the sensor's full-scale range."""


class ConfigError(InvalidInputError):
    """A TOML / JSON configuration is invalid."""


class ProvenanceError(InvalidInputError):
    """An operation would repeat one already recorded in the data's provenance (e.g. a second compensation)."""


class RunFolderError(InvalidInputError):
    """A run folder (lab, batch) holds another run, or has no complete manifest (a killed run)."""


class NotStaticError(InvalidInputError):
    """A recording that must be static (noise identification) shows motion."""


class ImunavWarning(UserWarning):
    """Something that may be a mistake but has a legitimate use (the command line prints it as one line)."""


class ConvergenceError(ImunavError, RuntimeError):
    """An iterative estimator did not converge."""


class MissingDependencyError(ImunavError, ImportError):
    """An optional dependency (extra) is needed for this feature.

    The message names the package and the ``pip install 'imunav[<extra>]'`` command that installs it.

    Parameters
    ----------
    package : str
        Name of the missing package as imported (e.g. ``"rosbags"``).
    extra : str
        The imunav extra that installs it (e.g. ``"ros"``).
    feature : str
        What the user asked for that needs it (e.g. ``"reading ROS bags"``).
    """

    def __init__(self, package: str, extra: str, feature: str) -> None:
        super().__init__(
            f"{feature} needs the optional package '{package}'. "
            f"Install it with: pip install 'imunav[{extra}]'"
        )
        self.package = package
        self.extra = extra
