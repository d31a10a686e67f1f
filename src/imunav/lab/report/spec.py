"""Datasheet-style specifications and pass / fail checks.

A specification is a TOML table of limits, one per parameter name, in
display units (the unit is stated and converted with :mod:`imunav.units`)::

    [spec.gyro_arw]           # angle random walk
    max = 0.3
    unit = "deg/sqrt(h)"

    [spec.accel_bias_instability]
    max = 50
    unit = "ug"

A parameter passes when its estimate lies within the limits.  With
``conservative=True`` the estimate's upper (lower) 95 % bound must lie within
the limits too, so that a pass is a statement with confidence.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from imunav.errors import ConfigError
from imunav.results import Result
from imunav.toml import read_toml
from imunav.units import from_display, to_display

__all__ = ["SpecLimit", "SpecCheck", "load_spec", "check_spec"]


@dataclass(frozen=True)
class SpecLimit:
    """Limits of one parameter, stored in SI, with the display unit.

    Attributes
    ----------
    name : str
        Parameter name (see :mod:`imunav.lab.report.catalog`), with or without axis.
    min_si, max_si : float or None
        Lower and upper limits, SI.
    unit : str
        Display unit the limits were given in (see :mod:`imunav.units`).
    description : str
        Free text.
    """

    name: str
    min_si: float | None
    max_si: float | None
    unit: str
    description: str = ""

    def describe(self) -> str:
        """The limits as text in the display unit (``"≤ 0.3 deg/sqrt(h)"``).

        Returns
        -------
        str
            The limits.
        """
        def d(x: float) -> str:
            return f"{to_display(x, self.unit):g}" if self.unit else f"{x:g}"

        if self.min_si is not None and self.max_si is not None:
            return f"{d(self.min_si)} … {d(self.max_si)} {self.unit}"
        if self.max_si is not None:
            return f"≤ {d(self.max_si)} {self.unit}"
        return f"≥ {d(self.min_si)} {self.unit}"  # type: ignore[arg-type]


@dataclass(frozen=True)
class SpecCheck(Result):
    """Outcome of checking one parameter against its limit.

    Attributes
    ----------
    name : str
        Parameter name.
    value_si : float
        The estimate, SI (NaN when not measured).
    sigma_si : float or None
        Its 1σ standard error, SI.
    limit : SpecLimit or None
        The limit applied.
    passed : bool or None
        The verdict; None without a limit.
    """
    name: str
    value_si: float
    sigma_si: float | None
    limit: SpecLimit | None
    passed: bool | None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary.

        Returns
        -------
        dict
            ``name``, ``value_si``, ``sigma_si``, ``limit`` (:meth:`SpecLimit.describe`), ``passed``.
        """
        return {
            "name": self.name,
            "value_si": self.value_si,
            "sigma_si": self.sigma_si,
            "limit": None if self.limit is None else self.limit.describe(),
            "passed": self.passed,
        }


def _conv(v: Any, unit: str, where: str) -> float:
    try:
        x = float(v)
    except (TypeError, ValueError) as e:
        raise ConfigError(f"{where}: limit {v!r} is not a number") from e
    if isinstance(v, bool) or not math.isfinite(x):
        raise ValueError(f"limit {v!r} is not a finite number")
    if unit in ("", "si", "SI"):
        return x
    if unit == "abs_ppm":
        return x * 1e-6
    return float(from_display(x, unit))


def load_spec(source: str | Path | Mapping[str, Any]) -> dict[str, SpecLimit]:
    """Read limits from a TOML file or an already-parsed mapping.

    Accepts a top-level ``[spec]`` table or the table itself; each entry has ``min`` and / or ``max``, a
    ``unit`` and an optional ``description``.

    Parameters
    ----------
    source : str or pathlib.Path or mapping
        The TOML file, or the parsed content.

    Returns
    -------
    dict of str to SpecLimit
        The limits by parameter name, SI.

    Raises
    ------
    ConfigError
        If the file does not exist or is invalid TOML, or an entry has unknown keys, no limit, a limit that
        is not a number, an unknown unit, or min > max.
    """
    if isinstance(source, Mapping):
        data = dict(source)
        where = "spec"
    else:
        p = Path(source)
        data = read_toml(p, "specification")
        where = str(p)
    table = data.get("spec", data)
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: [spec] must be a table of parameter limits")
    out: dict[str, SpecLimit] = {}
    for name, lim in table.items():
        if not isinstance(lim, Mapping):
            raise ConfigError(f"{where}: spec.{name} must be a table with min and/or max and unit")
        unknown = set(lim) - {"min", "max", "unit", "description"}
        if unknown:
            raise ConfigError(f"{where}: spec.{name} has unknown keys {sorted(unknown)}; allowed: min, max, unit, description")
        if "min" not in lim and "max" not in lim:
            raise ConfigError(f"{where}: spec.{name} needs min and/or max")
        unit = str(lim.get("unit", ""))
        try:
            mn = None if "min" not in lim else _conv(lim["min"], unit, f"{where}: spec.{name}")
            mx = None if "max" not in lim else _conv(lim["max"], unit, f"{where}: spec.{name}")
        except ValueError as e:
            raise ConfigError(f"{where}: spec.{name}: {e}") from e
        if mn is not None and mx is not None and mn > mx:
            raise ConfigError(f"{where}: spec.{name} has min > max")
        out[name] = SpecLimit(name, mn, mx, unit, str(lim.get("description", "")))
    return out


def check_spec(
    estimates: Mapping[str, tuple[float, float | None] | float],
    spec: Mapping[str, SpecLimit],
    *,
    conservative: bool = False,
) -> list[SpecCheck]:
    """Compare estimates ``{name: value_si | (value_si, sigma_si)}`` with the limits.

    Parameters without a limit get ``passed=None``; limits without an estimate
    are reported as failed checks with a NaN value (a spec item that was not
    measured cannot pass).

    A limit with only ``max`` bounds the magnitude ``|value|``.  With ``conservative=True`` the 95 % bound
    (value ± 1.96 σ) must lie within the limits too.

    Parameters
    ----------
    estimates : mapping of str to float or (float, float or None)
        ``{name: value_si | (value_si, sigma_si)}``.
    spec : mapping of str to SpecLimit
        Limits per concrete name (:func:`imunav.lab.report.catalog.expand_spec`).
    conservative : bool
        Require the 95 % bound inside the limits.

    Returns
    -------
    list of SpecCheck
        One check per estimate, then one per limit without estimate.
    """
    checks: list[SpecCheck] = []
    for name, est in estimates.items():
        v, s = (est if isinstance(est, tuple) else (est, None))
        lim = spec.get(name)
        if lim is None:
            checks.append(SpecCheck(name, float(v), s, None, None))
            continue
        k = 1.96 * (s or 0.0) if conservative else 0.0
        ok = True
        if lim.max_si is not None:
            ok &= abs(v) + k <= lim.max_si if lim.min_si is None else v + k <= lim.max_si
        if lim.min_si is not None:
            ok &= v - k >= lim.min_si
        checks.append(SpecCheck(name, float(v), s, lim, bool(ok)))
    for name, lim in spec.items():
        if name not in estimates:
            checks.append(SpecCheck(name, float("nan"), None, lim, False))
    return checks
