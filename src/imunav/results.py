"""The one result base: ``to_dict()`` for JSON and ``to_json(path)`` written atomically.

Every result dataclass of imunav derives from :class:`Result`.  ``to_dict()``
gives plain JSON types (arrays become lists, NaN / ±inf become ``None``:
strict JSON, never a ``NaN`` token) through :func:`imunav.files.jsonable`;
``to_json(path)`` writes that dictionary through
:func:`imunav.files.write_json` (temporary file beside the target, then
an atomic rename).  A result whose JSON shape is not simply its fields
overrides ``to_dict()``; ``to_json()`` follows the override.

This module sits at the bottom of the package: it imports nothing above
:mod:`imunav.files`.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imunav.files import jsonable, write_json
from imunav.rotation import euler_from_quat

__all__ = ["Result", "EulerMixin", "jsonable"]


class Result:
    """Base of the result dataclasses: ``to_dict()`` (strict JSON types) and ``to_json(path)``.

    Examples
    --------
    >>> import dataclasses, numpy as np
    >>> @dataclasses.dataclass(frozen=True)
    ... class Fit(Result):
    ...     value: np.ndarray
    >>> Fit(np.array([1.0, np.nan])).to_dict()
    {'value': [1.0, None]}
    """

    __slots__ = ()

    def to_dict(self) -> dict[str, Any]:
        """The fields as plain JSON types (arrays as lists, NaN / inf as ``None``).

        Returns
        -------
        dict
            One key per dataclass field.
        """
        return {f.name: jsonable(getattr(self, f.name)) for f in dataclasses.fields(self)}  # type: ignore[arg-type]

    def to_json(self, path: str | os.PathLike[str], indent: int | None = 2) -> Path:
        """Write :meth:`to_dict` as standard JSON to ``path``, atomically.

        Parameters
        ----------
        path : str or path-like
            The file to write (its folder is created if needed).
        indent : int or None
            JSON indentation; ``None`` for one line.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        return write_json(path, self.to_dict(), indent)


class EulerMixin:
    """Mixin of the types that hold an attitude ``q_nb`` ((N, 4) or (4,)): its ZYX Euler angles by :meth:`euler`.

    The naming table of ``docs/design.md`` makes ``euler()`` a method computed from ``q_nb`` on every
    result; this is its one implementation.
    """

    __slots__ = ()

    def euler(self) -> NDArray[np.float64]:
        """ZYX Euler angles (roll, pitch, yaw) of ``q_nb`` (:func:`imunav.rotation.euler_from_quat`).

        Returns
        -------
        numpy.ndarray, shape (N, 3), or (3,) for one attitude ``q_nb`` (4,)
            Roll, pitch, yaw, rad.
        """
        return euler_from_quat(self.q_nb)  # type: ignore[attr-defined]
