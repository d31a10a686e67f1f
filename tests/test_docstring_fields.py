"""fill_doc(**fields): a fragment's open words (``%(step)s``) filled per use, as the lab steps' run() get them."""

from __future__ import annotations

import inspect

import pytest

from imunav._docstrings import DOCS, fill_doc
from imunav.lab.steps import noise, temperature


def test_each_lab_step_run_names_its_own_option_table():
    for mod, step in ((noise, "noise"), (temperature, "temperature")):
        doc = inspect.getdoc(mod.run)
        assert f"``ctx.options`` (``[{step}]``)" in doc
        assert "%(" not in doc
        assert "\nReturns\n-------\nStepResult\n    " in doc  # the step's own description follows, indented


def test_a_field_left_open_is_an_error_naming_it():
    def f():
        """Summary.

        %(lab_step_run)s
        """

    with pytest.raises(KeyError, match=r"%\(step\)s"):
        fill_doc(f)
    assert "%(step)s" in DOCS["lab_step_run"]  # the fragment itself is left as it is
