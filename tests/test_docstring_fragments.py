"""Blocks a whole family of functions repeats verbatim in its docstrings, checked against one canonical text.

Docstrings are written out in full where they stand (nothing is filled in at import).  Where a family documents
the same options in the same words - the recording readers' options and return value, the attitude filters'
``reset`` / ``step`` / ``run`` - the canonical words are kept here, once: every docstring of the family carries
the block exactly, and a docstring of the package that starts one of these blocks (its first entry) carries all of
it, so a copy edited in one place only is caught.  To change the words, change them here and in every copy.

Each lab step's ``run`` documents its own option table (``[noise]`` in ``labsteps.noise``): checked too, as
those docstrings are alike but for that name.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from collections.abc import Iterator
from types import ModuleType

import pytest

import imunav.attitude
import imunav.io
import imunav.lab.steps

#: name -> (canonical block, written without indentation; the docstrings that carry it, by qualified name)
FRAGMENTS: dict[str, tuple[str, set[str]]] = {}

_READERS = {"imunav.io.csv.read_csv", "imunav.io.hdf5.read_hdf5", "imunav.io.mat.read_mat", "imunav.io.npz.read_npz",
            "imunav.io.parquet.read_parquet"}

FRAGMENTS["reader_units"] = ("""\
units : mapping of str to str, optional
    Declared unit of each group (``{"gyro": "deg/s", "accel": "g"}``, or ``"counts"``); default SI.
scales, offsets : mapping of str to float, optional
    For ``"counts"``: ``value_si = (counts - offset) * scale``.
fs : float, optional
    Sample rate, Hz, when the file has no time (``t = t0 + k / fs``).
t0 : float
    Time of the first sample with ``fs``, s.""", _READERS)

FRAGMENTS["reader_tail"] = ("""\
nan_policy : {"raise", "drop", "interpolate"}
    What to do with NaN samples.
mag_unit : str, optional
    Unit of the magnetometer (kept as stored).
meta : mapping, optional
    Entries added to the recording's ``meta``.""", _READERS)

FRAGMENTS["reader_array_columns"] = ("""\
columns : mapping of str to str, optional
    Where each group is stored (e.g. ``{"gyro": "imu/gyr"}``); by default found by name.""",
                                     {"imunav.io.hdf5.read_hdf5", "imunav.io.mat.read_mat", "imunav.io.npz.read_npz"})

FRAGMENTS["reader_returns"] = ("""\
Returns
-------
ImuData
    The recording, SI.

Raises
------
FileFormatError
    If the file is missing, unreadable, or lacks a required group (the message lists what was found).
NonFiniteError, TimeOrderError, ShapeError, UnitError
    From the validation of the values.""", _READERS - {"imunav.io.csv.read_csv"})

_ATT = "imunav.attitude."

FRAGMENTS["attitude_reset"] = ("""\
q0 : array_like, shape (4,)
    Attitude ``q_nb`` [w, x, y, z], body (FRD) to NED (normalised here).""",
                               {_ATT + "_base.AttitudeReset.reset", _ATT + "mahony.Mahony.reset",
                                _ATT + "mekf.MEKF.reset", _ATT + "ukf.UKF.reset"})

FRAGMENTS["attitude_reset_raises"] = ("""\
Raises
------
ShapeError
    If ``q0`` is not a (4,) quaternion.
NonFiniteError
    If ``q0`` is zero or not finite.""", FRAGMENTS["attitude_reset"][1])

FRAGMENTS["attitude_step"] = ("""\
Parameters
----------
gyro : array_like, shape (3,)
    Angular rate, body axes (FRD), rad/s.
accel : array_like, shape (3,)
    Specific force, body axes, m/s² (any unit: only its direction is used).
mag : array_like, shape (3,), or None
    Magnetic field, body axes (any unit); None for a 6D update.
dt : float
    Time since the previous sample, s, > 0.

Returns
-------
numpy.ndarray, shape (4,)
    The new attitude ``q_nb``.

Raises
------
InvalidInputError
    If ``dt`` is not finite and positive, or the rate exceeds 1e4 rad/s (not rad/s).
ShapeError
    If a sample is not a 3-vector.
NonFiniteError
    If a sample is not finite.""", {_ATT + f"{m}.step" for m in ("complementary.Complementary", "madgwick.Madgwick",
                                                                 "mahony.Mahony", "mekf.MEKF", "ukf.UKF")})

_RUNS = {_ATT + f"{m}.run" for m in ("complementary.Complementary", "madgwick.Madgwick", "mahony.Mahony",
                                     "mekf.MEKF", "smoother.Smoother", "ukf.UKF")}

FRAGMENTS["attitude_run"] = ("""\
data : ImuData
    The recording (SI: rad/s, m/s²; magnetometer in any unit), body FRD.
q0 : array_like, shape (4,), optional
    Initial attitude ``q_nb`` (default: :func:`imunav.attitude.alignment.align` of the first accelerometer
    / magnetometer sample).""", _RUNS)

FRAGMENTS["attitude_run_raises"] = ("""\
Raises
------
InvalidInputError
    If ``data`` is not an ImuData with at least 2 samples, ``use_mag=True`` without a magnetometer, or a
    rate exceeds 1e4 rad/s.""", _RUNS)


def _docstrings(package: ModuleType) -> Iterator[tuple[str, str]]:
    """(qualified name, cleaned docstring) of every function, class and method a module of ``package`` defines."""
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            if getattr(obj, "__module__", None) != info.name or not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            yield f"{info.name}.{name}", inspect.getdoc(obj) or ""
            if inspect.isclass(obj):
                for mname, member in vars(obj).items():
                    f = member.fget if isinstance(member, property) else getattr(member, "__func__", member)
                    if inspect.isfunction(f) and f.__doc__:
                        yield f"{info.name}.{name}.{mname}", inspect.cleandoc(f.__doc__)


def _first_entry(block: str) -> str:
    """The block's first entry: its section header if it has one, and its first ``name : type`` line with the
    first line of its description."""
    lines = block.split("\n")
    head = 2 if set(lines[1]) == {"-"} else 0
    return "\n".join(lines[: head + 2])


def fragment_problems(block: str, members: set[str], docs: dict[str, str]) -> list[str]:
    """What is wrong with one family's copies of ``block`` in ``docs`` (empty: nothing)."""
    problems = [f"{name}: the block is not there word for word" for name in sorted(members) if block not in docs[name]]
    entry = _first_entry(block)
    problems += [f"{name}: starts the block but does not carry all of it (or is missing from the family)"
                 for name, doc in sorted(docs.items()) if entry in doc and name not in members]
    return problems


@pytest.fixture(scope="module")
def package_docs() -> dict[str, str]:
    return dict(d for pkg in (imunav.io, imunav.attitude) for d in _docstrings(pkg))


@pytest.mark.parametrize("name", sorted(FRAGMENTS))
def test_every_copy_of_a_shared_block_is_the_canonical_text(name, package_docs):
    block, members = FRAGMENTS[name]
    assert fragment_problems(block, members, package_docs) == []


def test_a_copy_edited_in_one_place_only_is_caught():
    block, members = FRAGMENTS["reader_tail"]
    docs = {name: f"Summary.\n\nParameters\n----------\n{block}" for name in members}
    assert fragment_problems(block, members, docs) == []
    some = sorted(members)[0]
    docs[some] = docs[some].replace("What to do with NaN samples.", "What to do with NaNs.")
    assert fragment_problems(block, members, docs) == [f"{some}: the block is not there word for word"]
    docs["imunav.io.other.read_other"] = f"Summary.\n\n{block.replace('Unit of the magnetometer', 'Its unit')}"
    assert "imunav.io.other.read_other: starts the block" in fragment_problems(block, members, docs)[1]


def test_each_lab_step_run_names_its_own_option_table():
    steps = [i.name for i in pkgutil.iter_modules(imunav.lab.steps.__path__) if not i.name.startswith("_")]
    assert len(steps) >= 8
    for step in steps:
        doc = inspect.getdoc(importlib.import_module(f"imunav.lab.steps.{step}").run)
        assert f"``ctx.options`` (``[{step}]``)" in doc, step
