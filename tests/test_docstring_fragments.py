"""Shared numpydoc fragments (imunav._docstrings): filled at import, indented like their placeholder."""

from __future__ import annotations

import inspect

import pytest

from imunav._docstrings import DOCS, fill_doc
from imunav.attitude import Madgwick
from imunav.io.npz import read_npz


def test_filled_docstrings_carry_no_placeholder_and_parse_as_numpydoc():
    """A reader and a filter method, as a user gets them: every line of the fragment is there, indented under
    its section, and no ``%(`` placeholder is left."""
    doc = inspect.getdoc(read_npz)
    assert "%(" not in doc and "%(" not in Madgwick.step.__doc__
    assert "nan_policy : {\"raise\", \"drop\", \"interpolate\"}\n    What to do with NaN samples." in doc
    assert "Raises\n------\nFileFormatError\n" in doc
    step = inspect.getdoc(Madgwick.step)
    assert "dt : float\n    Time since the previous sample, s, > 0." in step
    # numpydoc sees every parameter of step (the docstring test checks the whole package the same way)
    numpydoc = pytest.importorskip("numpydoc.docscrape")
    names = [p.name for p in numpydoc.FunctionDoc(Madgwick.step)["Parameters"]]
    assert names == ["gyro", "accel", "mag", "dt"]


def test_fill_doc_indents_each_fragment_line_like_its_placeholder():
    def f():
        """Summary.

            %(att_q0)s
        """

    fill_doc(f)
    want = "\n".join("            " + ln for ln in DOCS["att_q0"].split("\n"))
    assert want in f.__doc__


def test_unknown_placeholder_is_an_error_at_import():
    def g():
        """Summary.

        %(no_such_fragment)s
        """

    with pytest.raises(KeyError, match="no_such_fragment"):
        fill_doc(g)
