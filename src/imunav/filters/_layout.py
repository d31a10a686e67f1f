"""Named layouts of kernel vectors (private): offsets generated from ``(name, size)`` tuples.

A numba kernel reads a packed float or integer vector through constant offsets (``prm[PRM.arw + j]``, never
``prm[4 + j]``).  :func:`named_layout` turns a tuple of ``(name, size)`` pairs into a namedtuple of start offsets
and the total size; numba freezes a module-level namedtuple of integers as compile-time constants, so reading
``LAYOUT.name`` inside a kernel costs nothing.  The layout tests (``tests/filters/test_kernel_layouts.py``) check
that the offsets are contiguous and follow their tuples.
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Sequence
from typing import Any


def named_layout(name: str, fields: Sequence[tuple[str, int]]) -> tuple[Any, int]:
    """Offsets of a packed vector from its ``(field, size)`` pairs, in order.

    Parameters
    ----------
    name : str
        Name of the generated namedtuple type (e.g. ``"GinsParams"``).
    fields : sequence of (str, int)
        Field names (valid identifiers, unique) and their sizes (>= 1), in packing order.

    Returns
    -------
    offsets : namedtuple
        One integer per field: the index of its first element.
    size : int
        Total length of the vector.

    Raises
    ------
    ValueError
        If a name repeats or a size is not a positive integer.

    Examples
    --------
    >>> lay, n = named_layout("Demo", (("a", 3), ("b", 1)))
    >>> lay.a, lay.b, n
    (0, 3, 4)
    """
    names = [f for f, _ in fields]
    if len(set(names)) != len(names):
        raise ValueError(f"named_layout {name}: repeated field in {names}")
    starts = []
    total = 0
    for f, size in fields:
        if not (isinstance(size, int) and size >= 1):
            raise ValueError(f"named_layout {name}: field {f!r} has size {size!r}; sizes are integers >= 1")
        starts.append(total)
        total += size
    return namedtuple(name, names)(*starts), total
