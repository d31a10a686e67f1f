"""Every public function and class has a numpydoc docstring that a user of the package can read.

The public API is walked by importing every module of ``src/imunav`` whose dotted name has no part with a
leading underscore (``imunav.cli`` excluded: typer's ``--help`` is its documentation), and taking each
function and class that the module defines under a public name, or re-exports through ``__all__``, with the
public methods of those classes.  For each one (numpydoc's own parser, :mod:`numpydoc.docscrape`):

- a callable with parameters has a ``Parameters`` section that names each of them (a class: those of its
  ``__init__``; a dataclass may name its fields under ``Attributes`` instead, numpydoc's section for them);
- a function that returns something (a return annotation other than ``None``, or a ``return <value>``)
  has a ``Returns`` (or ``Yields``) section;
- every entry of ``Parameters``, ``Attributes`` and ``Returns`` has an indented description under its
  ``name : type`` line (a description written in the type slot renders as a type);
- a function whose own body raises an :mod:`imunav.errors` exception (``raise ShapeError(...)``) names it,
  or one of its base classes, under ``Raises`` (exceptions raised by the helpers it calls are not traced);
- no docstring points at the project's private notes (``../shared``, ``specs/`` digests), which a user of
  the installed package does not have: references go to published sources.

The checks run on synthetic objects first, so the test is shown to fail on a bad docstring.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pkgutil
import re
import textwrap
import warnings
from collections.abc import Callable, Iterator

import pytest

docscrape = pytest.importorskip("numpydoc.docscrape")

import imunav  # noqa: E402
from imunav import errors as _errors  # noqa: E402

# Modules not yet brought to numpydoc (their sections are not checked); "pkg.*" stands for every module of a
# package.  Empty: every public module is checked.
NOT_YET_DONE: set[str] = set()

# Modules whose docstrings still cite the project's private notes instead of the published source (same form).
NOTES_NOT_YET_DONE: set[str] = set()

# The two modules that locate the shared data folder document where they look: ``../shared/data`` is their
# behaviour there, not a reference.
SHARED_DATA_LOOKUP = {"imunav.io.datasets", "imunav.lab.steps.recordings"}

# ``../shared``, ``specs/``, "digest", and the file names of the project's digests of its sources
PRIVATE_NOTES = re.compile(r"\.\./shared|\bspecs/|\bdigest\b|references\.md|ahrs-sensor-errors|airdata-doppler-wind"
                           r"|attitude-kf-external|imu-error-calibration|zupt-lstm-pedestrian", re.IGNORECASE)


def _listed(modname: str, names: set[str]) -> bool:
    return modname in names or any(n.endswith(".*") and modname.startswith(n[:-1]) for n in names)


def _public_modules() -> list[str]:
    names = ["imunav"]
    for info in pkgutil.walk_packages(imunav.__path__, "imunav."):
        if any(part.startswith("_") for part in info.name.split(".")) or info.name.startswith("imunav.cli"):
            continue
        names.append(info.name)
    return sorted(names)




def _public_objects(mod) -> Iterator[tuple[str, object]]:
    """(qualified name, object) of the functions and classes of ``mod``'s public API."""
    exported = set(getattr(mod, "__all__", ()))
    for name, obj in vars(mod).items():
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        own = getattr(obj, "__module__", None) == mod.__name__ and not name.startswith("_")
        if not (own or (name in exported and str(getattr(obj, "__module__", "")).startswith("imunav"))):
            continue
        yield f"{obj.__module__}.{obj.__qualname__}", obj
        if inspect.isclass(obj):
            for mname, member in vars(obj).items():
                if mname.startswith("_"):
                    continue
                if isinstance(member, (staticmethod, classmethod)):
                    member = member.__func__
                if inspect.isfunction(member):
                    yield f"{obj.__module__}.{obj.__qualname__}.{mname}", member


def _signature_params(obj) -> list[str]:
    target = obj
    if inspect.isclass(obj):
        if not any("__init__" in vars(c) for c in obj.__mro__ if c.__module__.startswith("imunav")
                   or c.__module__ == __name__):
            return []  # the __init__ of a builtin base (an exception type): nothing of the package to document
        target = obj.__init__
    try:
        sig = inspect.signature(target)
    except (TypeError, ValueError):
        return []
    out = []
    for i, p in enumerate(sig.parameters.values()):
        if (i == 0 and p.name in ("self", "cls")) or p.name.startswith("_"):
            continue  # the instance, or a private keyword (not part of the public API)
        if p.kind is p.VAR_POSITIONAL:
            out.append("*" + p.name)
        elif p.kind is p.VAR_KEYWORD:
            out.append("**" + p.name)
        else:
            out.append(p.name)
    return out


def _returns_value(func) -> bool:
    """True when ``func`` returns something: an annotation other than None, else a ``return <value>``."""
    ann = inspect.signature(func).return_annotation
    if ann is not inspect.Signature.empty:
        return ann not in (None, "None", "NoReturn", "typing.NoReturn")
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return False
    return any(isinstance(n, ast.Return) and n.value is not None and not (
        isinstance(n.value, ast.Constant) and n.value.value is None) for n in _own_body(tree.body[0]))


_ERRORS = {n: c for n, c in vars(_errors).items() if isinstance(c, type) and issubclass(c, Exception)}


def _own_body(fn: ast.AST) -> Iterator[ast.AST]:
    """The nodes of a function's own body, not of nested functions / classes."""
    for child in ast.iter_child_nodes(fn):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        yield child
        yield from _own_body(child)


def _raised_errors(func) -> set[str]:
    """Names of the imunav.errors exceptions that ``func``'s own body raises."""
    try:
        fn = ast.parse(textwrap.dedent(inspect.getsource(func))).body[0]
    except (OSError, TypeError, SyntaxError, IndexError):
        return set()
    out = set()
    for n in _own_body(fn):
        if isinstance(n, ast.Raise) and isinstance(n.exc, ast.Call):
            name = getattr(n.exc.func, "id", None) or getattr(n.exc.func, "attr", None)  # X(...) or errors.X(...)
            if name in _ERRORS:
                out.add(name)
    return out


def _section_names(entries) -> set[str]:
    names = set()
    for entry in entries:
        for name in entry.name.split(","):  # "x, y : float"
            names.add(name.strip())
    return names


def docstring_problems(qualname: str, obj, check_sections: bool = True, check_notes: bool = True) -> list[str]:
    """The rules above, applied to one function or class; an empty list when it passes."""
    doc = inspect.getdoc(obj) if inspect.isclass(obj) else obj.__doc__
    doc = inspect.cleandoc(doc) if doc else ""
    problems = []
    if check_notes and PRIVATE_NOTES.search(doc) and obj.__module__ not in SHARED_DATA_LOOKUP:
        problems.append(f"{qualname}: refers to the project's private notes "
                        f"({PRIVATE_NOTES.search(doc).group(0)!r}); cite the published source")
    if not check_sections:
        return problems
    if not doc:
        return [*problems, f"{qualname}: no docstring"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            parsed = docscrape.NumpyDocString(doc)
        except Exception as exc:  # numpydoc raises ValueError on a malformed section
            return [*problems, f"{qualname}: numpydoc cannot parse the docstring ({exc})"]
    params = _signature_params(obj)
    if params:
        named = _section_names(parsed["Parameters"]) | _section_names(parsed["Other Parameters"])
        if inspect.isclass(obj) and dataclasses.is_dataclass(obj):
            named |= _section_names(parsed["Attributes"])
        missing = [p for p in params if p not in named and p.lstrip("*") not in named]
        if not parsed["Parameters"] and not (dataclasses.is_dataclass(obj) and parsed["Attributes"]):
            problems.append(f"{qualname}: no Parameters section (parameters: {', '.join(params)})")
        elif missing:
            problems.append(f"{qualname}: Parameters does not name {', '.join(missing)}")
    for sec in ("Parameters", "Attributes", "Returns"):
        for e in parsed[sec]:
            if not "".join(e.desc).strip():
                problems.append(f"{qualname}: {sec} entry '{e.name or e.type}' has no description")
    if inspect.isfunction(obj) and _returns_value(obj) and not (parsed["Returns"] or parsed["Yields"]):
        problems.append(f"{qualname}: returns a value but has no Returns section")
    if inspect.isfunction(obj):
        listed = {w.strip("~.`:").split(".")[-1] for e in parsed["Raises"]
                  for w in f"{e.name} {e.type}".replace(",", " ").split()}
        missing = sorted(r for r in _raised_errors(obj)
                         if not any(c.__name__ in listed for c in _ERRORS[r].__mro__))
        if missing:
            problems.append(f"{qualname}: raises {', '.join(missing)} but its Raises section does not say so")
    return problems


def _all_problems(include_not_done: bool = False) -> Iterator[str]:
    seen: set[int] = set()
    for modname in _public_modules():
        mod = importlib.import_module(modname)
        doc = mod.__doc__ or ""
        if PRIVATE_NOTES.search(doc) and modname not in SHARED_DATA_LOOKUP and not _listed(modname, NOTES_NOT_YET_DONE):
            yield f"{modname} (module docstring): refers to the project's private notes; cite the published source"
        for qualname, obj in _public_objects(mod):
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            owner = obj.__module__
            yield from docstring_problems(qualname, obj, include_not_done or not _listed(owner, NOT_YET_DONE),
                                          include_not_done or not _listed(owner, NOTES_NOT_YET_DONE))


# ---------------------------------------------------------------------------------------------------------
# the checker, on synthetic cases


def _good(x: float, y: float = 1.0) -> float:
    """Sum.

    Parameters
    ----------
    x, y : float
        Addends, m.

    Returns
    -------
    float
        ``x + y``, m.
    """
    return x + y


def _no_params(x: float, y: float) -> None:
    """Prints the sum of x and y."""
    print(x + y)


def _missing_one(x: float, y: float) -> float:
    """Sum.

    Parameters
    ----------
    x : float
        First addend.

    Returns
    -------
    float
        The sum.
    """
    return x + y


def _no_returns(x):
    """Double.

    Parameters
    ----------
    x : float
        Value.
    """
    return 2 * x


def _private_ref(x: float) -> None:
    """Does nothing (see the digest, ../shared/specs/foo.md §2).

    Parameters
    ----------
    x : float
        Ignored.
    """


def _raises_undocumented(x: float) -> float:
    """Square root.

    Parameters
    ----------
    x : float
        Value, >= 0.

    Returns
    -------
    float
        sqrt(x).

    Raises
    ------
    InvalidInputError
        If ``x`` is not finite (a base class of NonFiniteError: enough).
    """
    if x != x:
        raise _errors.NonFiniteError("x is NaN")
    if x < 0:
        raise ConvergenceError("no")  # noqa: F821 - never run; only its name is read
    return x**0.5


def _type_slot(x: float) -> float:
    """Half.

    Parameters
    ----------
    x : the value to halve, m.

    Returns
    -------
    float
        ``x / 2``, m.
    """
    return x / 2


@dataclasses.dataclass
class _GoodResult:
    """A result.

    Attributes
    ----------
    a : float
        Something, m.
    b : int
        Count.
    """

    a: float
    b: int


class _BadClass:
    """A class without its parameters documented."""

    def __init__(self, gain: float):
        self.gain = gain


@pytest.mark.parametrize("func, expected", [
    (_good, None),
    (_no_params, "no Parameters section"),
    (_missing_one, "does not name y"),
    (_no_returns, "no Returns section"),
    (_private_ref, "private notes"),
    (_raises_undocumented, "raises ConvergenceError but its Raises section"),
    (_type_slot, "Parameters entry 'x' has no description"),
    (_GoodResult, None),
    (_BadClass, "no Parameters section (parameters: gain)"),
])
def test_checker_on_synthetic_cases(func: Callable, expected: str | None):
    found = docstring_problems(func.__qualname__, func)
    if expected is None:
        assert found == []
    else:
        assert len(found) == 1 and expected in found[0], found


def test_walker_finds_public_api():
    mods = _public_modules()
    assert "imunav.rotation" in mods and "imunav.noise.allan" in mods
    assert not any(m.startswith("imunav.cli") or "._" in m for m in mods)
    names = {q for q, _ in _public_objects(importlib.import_module("imunav.rotation"))}
    assert "imunav.rotation.quat_multiply" in names


def test_every_public_docstring_is_numpydoc_and_cites_published_sources():
    problems = list(_all_problems())
    assert not problems, f"{len(problems)} docstring problems:\n" + "\n".join(problems)
