"""One validation layer for the numeric options of every command.

Every numeric option (``int`` or ``float``) of every command has a declared
domain here: finite, positive, integer, in a range.  :func:`check_params`
checks the parsed values before the command runs (:class:`imunav.cli._errors.ImunavGroup`
installs it on every command) and refuses a value outside its domain with one
line naming the flag, e.g. ``--gravity nan: must be a finite number > 0 (m/s^2)``.
Typer already refuses text that is not a number; NaN and ±inf parse as floats
and are refused here.

:data:`DOMAINS` is keyed by the flag (``"--fs"``), or by ``"<command path> <flag>"``
(``"attitude benchmark --workers"``) where one flag means different things in
different commands; :func:`domain_of` looks the command's key up first.  The
hostile-case tests (``tests/test_cli_hostile.py``) derive their cases from
these domains and check that every numeric option has one.

Path options have a declared role (:func:`path_role`: input, input folder,
output file, report folder, run folder), and :func:`check_paths` applies the
one output check (:func:`imunav.files.check_outputs`) to every command from
these roles, before the command runs: no output may equal, contain or sit
inside an input, whatever the command itself checks later.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from imunav.errors import InvalidInputError
from imunav.files import check_outputs

__all__ = ["DOMAINS", "Domain", "check_params", "check_paths", "domain_of", "flag_of", "COLUMNS_EXAMPLE", "parse_json", "parse_numbers",
           "path_role"]


@dataclass(frozen=True)
class Domain:
    """The values a numeric option accepts.

    Attributes
    ----------
    integer : bool
        Integers only (else real numbers).
    lo, hi : float or None
        Bounds (None: unbounded).
    lo_open, hi_open : bool
        The bound itself is excluded.
    nonzero : bool
        Zero is excluded (e.g. a scale factor).
    unit : str
        The unit, for the message.
    """

    integer: bool = False
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    nonzero: bool = False
    unit: str = ""

    def describe(self) -> str:
        """The domain in words, e.g. ``"a finite number > 0 (Hz)"``.

        Returns
        -------
        str
            The description used in messages.
        """
        what = "an integer" if self.integer else "a finite number"
        parts = []
        if self.lo is not None and self.hi is not None:
            parts.append(f"in {'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}{')' if self.hi_open else ']'}")
        elif self.lo is not None:
            parts.append(f"{'>' if self.lo_open else '>='} {self.lo:g}")
        elif self.hi is not None:
            parts.append(f"{'<' if self.hi_open else '<='} {self.hi:g}")
        if self.nonzero:
            parts.append("not 0")
        return " ".join([what, *parts]) + (f" ({self.unit})" if self.unit else "")

    def contains(self, value: Any) -> bool:
        """Whether ``value`` is in the domain.

        Parameters
        ----------
        value : object
            The parsed option value.

        Returns
        -------
        bool
            True when it is a number of the right kind within the bounds.
        """
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        v = float(value)
        if not math.isfinite(v) or (self.integer and v != int(v)) or (self.nonzero and v == 0):
            return False
        if self.lo is not None and (v < self.lo or (self.lo_open and v == self.lo)):
            return False
        return not (self.hi is not None and (v > self.hi or (self.hi_open and v == self.hi)))


def _real(lo: float | None = None, hi: float | None = None, *, lo_open: bool = False, hi_open: bool = False,
          nonzero: bool = False, unit: str = "") -> Domain:
    return Domain(False, lo, hi, lo_open, hi_open, nonzero, unit)


def _int(lo: float | None = None, hi: float | None = None, unit: str = "") -> Domain:
    return Domain(True, lo, hi, unit=unit)


def _pos(unit: str = "", hi: float | None = None) -> Domain:
    return _real(0.0, hi, lo_open=True, unit=unit)


def _nonneg(unit: str = "", hi: float | None = None) -> Domain:
    return _real(0.0, hi, unit=unit)


_SEED = _int(0, 2**63 - 1)
_COUNT = _int(1, 10**9)
_RUNS = _int(1, 10**9)
_WORKERS = _int(1, 4096)
_LAT = _real(-90.0, 90.0, unit="deg")
_GRAVITY = _real(0.0, 100.0, lo_open=True, unit="m/s^2")
_SCALE = _pos("SI units per count", 1e6)  # one scale for three axes: a negative one mirrors the triad
_PROB = _real(0.0, 1.0, lo_open=True, hi_open=True)

#: flag (or "<command path> <flag>") -> domain; see the module docstring.
DOMAINS: dict[str, Domain] = {
    # recordings and readers
    "--fs": _pos("Hz", 1e7),
    "--start": _nonneg("s from the recording's start", 1e9),
    "--end": _pos("s from the recording's start", 1e9),
    "--instance": _int(0, 255),
    "--skiprows": _int(0, 10**9),
    "--gyro-scale": _SCALE,
    "--accel-scale": _SCALE,
    "--seed": _SEED,
    # info
    "info --window": _pos("s", 1e6),
    "--min-static": _pos("s", 1e6),
    "--gyro-full-scale-dps": _pos("deg/s", 1e6),
    "--accel-full-scale-g": _pos("g", 1e6),
    "--max-rows": _int(0, 10**6),
    # noise
    "--gm": _int(0, 10),
    # simulate / batch simulate / attitude montecarlo / gins / airdata
    "--dwell": _pos("s", 1e7),
    "--transition": _nonneg("s", 1e7),
    "--duration": _pos("s", 1e9),
    "--lat-deg": _LAT,
    "--latitude-deg": _LAT,
    "--h-m": _real(-12000.0, 1e6, unit="m"),
    "--spread": _nonneg("relative, 1 = 100 %", 10.0),
    "--static": _pos("s", 1e9),
    "n_units": _COUNT,
    "--start-sow": _real(0.0, 604800.0, hi_open=True, unit="s of GPS week"),
    # calibrate
    "--gravity": _GRAVITY,
    "--expected-angle-deg": _real(-3600.0, 3600.0, nonzero=True, unit="deg"),
    "--init-s": _pos("s", 1e7),
    "--wait-s": _pos("s", 1e7),
    "--order": _int(0, 20),
    "--field-norm": _pos("the data's unit", 1e12),
    "--min-coverage": _real(0.0, 1.0),
    "--temp-c": _real(-273.15, 1000.0, unit="degC"),
    # workers and runs
    "--workers": _WORKERS,
    "attitude benchmark --workers": _int(0, 4096),
    "--runs": _COUNT,
    "--threads": _int(1, 4096),
    # zupt
    "--threshold": _pos("", 1e12),
    "zupt run --states": _int(9, 15),
    "--zaru-min-s": _nonneg("s", 1e6),
    "--margin-s": _nonneg("s", 1e6),
    "--accel-noise-std": _pos("m/s^2", 1e6),
    "--windows-per-trial": _COUNT,
    "--epochs": _COUNT,
    "--layers": _int(1, 100),
    "--hidden": _int(1, 100000),
    "--budget-s": _pos("s", 1e7),
    "--shoe-threshold": _pos("", 1e12),
    "--limit": _COUNT,
    # gins
    "gins run --states": _int(15, 21),
    "gins outage-test --states": _int(15, 21),
    "--converge": _nonneg("s", 1e7),
    "--every": _pos("s", 1e7),
    "--length": _pos("s", 1e7),
    "gins outage-test --truth-std": _nonneg("m, the reference's horizontal sigma", 1e3),
    # airdata
    "--tas": _pos("m/s", 1000.0),
    "--altitude": _real(-500.0, 30000.0, unit="m"),
    "--rate-ads": _pos("Hz", 1e4),
    "--rate-doppler": _pos("Hz", 1e4),
    "--gate-m": _pos("", 1e6),
    "--alpha": _PROB,
    "--magnitude": _real(-1e6, 1e6),
    "--onset": _int(1, 10**7),
    "airdata faults --window": _int(1, 10**6),
    "--pfa": _PROB,
    "--horizon": _int(1, 10**6),
}


def flag_of(param: Any) -> str:
    """The flag a user types for a click parameter (its longest ``--`` name; an argument's name).

    Parameters
    ----------
    param : click.Parameter
        The parameter.

    Returns
    -------
    str
        E.g. ``"--gravity"``, or ``"n_units"`` for an argument.
    """
    longs = [o for o in getattr(param, "opts", []) if o.startswith("--")]
    return max(longs, key=len) if longs else str(param.name)


def domain_of(command_path: str, param: Any) -> Domain | None:
    """The declared domain of a parameter of the command ``command_path`` (e.g. ``"calibrate mag"``).

    Parameters
    ----------
    command_path : str
        The command's words after ``imunav``.
    param : click.Parameter
        The parameter.

    Returns
    -------
    Domain or None
        None when the parameter has none (non-numeric parameters).
    """
    flag = flag_of(param)
    words = command_path.split()
    for k in range(len(words), 0, -1):
        d = DOMAINS.get(" ".join(words[:k]) + " " + flag)
        if d is not None:
            return d
    return DOMAINS.get(flag)


def numeric(param: Any) -> bool:
    """Whether a parameter takes an ``int`` or ``float`` (not ``bool``).

    Parameters
    ----------
    param : click.Parameter
        The parameter.

    Returns
    -------
    bool
        True for numeric parameters.
    """
    ann = getattr(getattr(param, "type_descriptor", None), "annotation", None)
    if ann is None:
        t = getattr(param, "type", None)
        name = getattr(t, "name", "")
        return name in ("integer", "float")
    return ann in (int, float)


def check_params(command_path: str, params: list[Any], values: Mapping[str, Any]) -> None:
    """Refuse, before the command runs, a numeric option value outside its declared domain.

    Parameters
    ----------
    command_path : str
        The command's words after ``imunav`` (for per-command domains).
    params : list of click.Parameter
        The command's parameters.
    values : mapping
        Parameter name -> parsed value (None: not given).

    Raises
    ------
    InvalidInputError
        Naming the flag, the value and the domain; or naming a text option given an empty value.
    """
    for p in params:
        v = values.get(p.name)
        if isinstance(v, str) and not v.strip() and getattr(p, "default", None) not in ("",):
            raise InvalidInputError(f"{flag_of(p)} is empty; give a value (see --help) or leave the option out")
        if v is None or not numeric(p):
            continue
        d = domain_of(command_path, p)
        if d is None:
            d = Domain()  # undeclared: at least finite
        for x in (v if isinstance(v, (list, tuple)) else [v]):
            if not d.contains(x):
                raise InvalidInputError(f"{flag_of(p)} {x!r}: must be {d.describe()}")


def parse_numbers(flag: str, text: str, domain: Domain | None = None, *, count: int | None = None,
                  example: str = "") -> list[Any]:
    """The numbers of a comma-separated option value, each checked against ``domain``: the one parser of
    list-valued options (``--orders 1,2,3``, ``--shifts 0,60``, ``--wind 1,2,0``, ``cal.json@25``).

    Parameters
    ----------
    flag : str
        The option (or argument) as the user typed it, for the message.
    text : str
        Its value.
    domain : Domain, optional
        The domain of each number (integers when ``domain.integer``); default: any finite number.
    count : int, optional
        How many numbers the value must have.
    example : str, optional
        A valid value, for the message.

    Returns
    -------
    list of int or float
        The numbers, in order (ints for an integer domain).

    Raises
    ------
    InvalidInputError
        Naming the flag and the value, when a part is not a number, is outside ``domain``, or the count is wrong.
    """
    d = domain or Domain()
    hint = f" (e.g. {example})" if example else ""
    parts = [p.strip() for p in str(text).split(",")]
    what = f"{count} comma-separated" if count else "comma-separated"
    out: list[Any] = []
    for p in parts:
        try:
            v: Any = int(p) if d.integer else float(p)
        except ValueError:
            raise InvalidInputError(f"{flag} {text!r}: {p!r} is not {'an integer' if d.integer else 'a number'}; "
                                    f"give {what} values, each {d.describe()}{hint}") from None
        if not d.contains(v):
            raise InvalidInputError(f"{flag} {text!r}: {p} must be {d.describe()}{hint}")
        out.append(v)
    if count is not None and len(out) != count:
        raise InvalidInputError(f"{flag} {text!r}: give {what} values, not {len(out)}{hint}")
    return out


def parse_json(flag: str, text: str, example: str = "") -> Any:
    """A JSON option value (``--columns '{"gyro": [...]}'``), parsed in the validation layer.

    Parameters
    ----------
    flag : str
        The option, for the message.
    text : str
        Its value.
    example : str, optional
        A valid value, for the message.

    Returns
    -------
    object
        The parsed value.

    Raises
    ------
    InvalidInputError
        Naming the flag, when the text is not valid JSON.
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InvalidInputError(f"{flag} {text!r}: not valid JSON ({exc.msg} at column {exc.colno})"
                                + (f"; write e.g. {example}" if example else "")) from None


#: A valid ``--columns`` value, for messages.
COLUMNS_EXAMPLE = '\'{"gyro": ["gx", "gy", "gz"], "accel": ["ax", "ay", "az"]}\''


_FILE_OUTPUTS = {"--json", "--plot", "--psd-plot", "--kalibr", "--openvins", "--vins", "--px4-params",
                 "--imucal-out", "out", "--out", "simulate --segments",
                 "noise --profile"}
_INPUT_FOLDERS = {"directory", "folder"}
_RUN_FOLDERS = {"lab --out", "batch simulate --out", "batch calibrate --out", "batch noise --out", "batch gins --out"}
_REPORT_FOLDERS = {"--report", "gins simulate --out", "gins run --out", "gins outage-test --out"}


def path_role(command_path: str, flag: str) -> str:
    """The role of a path option: ``input``, ``input-folder``, ``output``, ``report-folder`` or ``run-folder``.

    Parameters
    ----------
    command_path : str
        The command's words after ``imunav`` (``"calibrate mag"``).
    flag : str
        The option's flag (:func:`flag_of`).

    Returns
    -------
    str
        The role.
    """
    key = f"{command_path} {flag}"
    if key in _RUN_FOLDERS:
        return "run-folder"
    if key in _REPORT_FOLDERS or flag in _REPORT_FOLDERS:
        return "report-folder"
    if flag in _INPUT_FOLDERS:
        return "input-folder"
    if flag in _FILE_OUTPUTS or key in _FILE_OUTPUTS:
        return "output"
    return "input"


def is_path(param: Any) -> bool:
    """Whether a parameter takes a file system path.

    Parameters
    ----------
    param : click.Parameter
        The parameter.

    Returns
    -------
    bool
        True for ``pathlib.Path`` parameters (optional or not).
    """
    ann = getattr(getattr(param, "type_descriptor", None), "annotation", None)
    return ann is not None and "Path" in str(ann)


def check_paths(command_path: str, params: list[Any], values: Mapping[str, Any]) -> None:
    """The output check of :func:`imunav.files.check_outputs` from the declared path roles, before the command.

    Parameters
    ----------
    command_path : str
        The command's words after ``imunav``.
    params : list of click.Parameter
        The command's parameters.
    values : mapping
        Parameter name -> parsed value (None: not given).

    Raises
    ------
    InvalidInputError
        When an output would equal, hold or sit inside an input (see :func:`imunav.files.check_outputs`).
    OSError
        When an output cannot be written there.
    """
    roles: dict[str, list[Any]] = {}
    for p in params:
        v = values.get(p.name)
        if v is None or not is_path(p):
            continue
        roles.setdefault(path_role(command_path, flag_of(p)), []).extend(v if isinstance(v, (list, tuple)) else [v])
    check_outputs([*roles.get("input", []), *roles.get("input-folder", [])], roles.get("output", []),
                  folders=roles.get("report-folder", []), run_folders=roles.get("run-folder", []),
                  inputs_exist=False)
