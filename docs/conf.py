"""Sphinx configuration of the imunav site (``make docs``; user guide, page "Install and first run").

The user guide (``guide/*.md``, one page per task) and the Markdown pages (conventions, changelog) go through
myst-parser, the API pages come from the numpydoc docstrings (autodoc + napoleon + autosummary), and the gallery page from a short lab run made by ``gallery.py``
before the build (cached in ``_generated/``, which is not committed).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))  # gallery.py
SRC = HERE.parent / "src"
if SRC.is_dir():  # a source checkout: document this tree even when another imunav is installed
    sys.path.insert(0, str(SRC))

import imunav  # noqa: E402

project = "imunav"
author = "imunav developers"
release = version = imunav.__version__
copyright = "imunav developers, MIT licence"

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
# only the pages of the site: the developer notes and the design digest stay Markdown files of the repository
exclude_patterns = ["_build", "_generated/lab", "dev", "design.md", "sim-errors.md", "README.md"]

autosummary_generate = True
# members defined in each module only: a package re-exporting them would document every object twice
autodoc_default_options = {"members": True, "show-inheritance": True, "ignore-module-all": True}
autodoc_typehints = "none"  # the numpydoc Parameters sections carry the types
autodoc_member_order = "bysource"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
myst_heading_anchors = 3
# The numpydoc type fields carry array shapes, e.g. "K : (n, m)", which the Python domain tries to link;
# a shape letter that is also an attribute name somewhere ("n") is then reported as an ambiguous target.
suppress_warnings = ["myst.header", "ref.python"]

html_theme = "alabaster"
html_title = f"imunav {release}"
html_static_path: list[str] = []


_LITERAL = re.compile(r"(``.*?``)")
_TABLE_ROW = re.compile(r"^\s*(\+[-=+]+\+|\|.*\|)\s*$")  # a grid-table border or row


def _escape_bars(line: str) -> str:
    """``|x|`` (a norm or an absolute value in the docstrings' plain-text maths) as text, not as a
    reStructuredText substitution; ``literal`` spans are left alone."""
    return "".join(part if part.startswith("``") else part.replace("|", "\\|") for part in _LITERAL.split(line))


def _plain_bars(app, what, name, obj, options, lines):
    """autodoc-process-docstring hook (after napoleon): escape ``|`` outside literal blocks, grid tables and
    doctests."""
    literal_indent = None
    for i, line in enumerate(lines):
        stripped = line.lstrip()
        indent = len(line) - len(stripped)
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if stripped.startswith(">>>") or _TABLE_ROW.match(line):
            continue
        lines[i] = _escape_bars(line)
        if stripped.endswith("::"):
            literal_indent = indent


def _public_modules(name: str = "imunav") -> set[str]:
    import importlib
    import pkgutil

    mod = importlib.import_module(name)
    out = {name}
    for info in pkgutil.iter_modules(getattr(mod, "__path__", [])):
        if not info.name.startswith("_"):
            out |= _public_modules(f"{name}.{info.name}")
    return out


def _check_every_module_listed(app) -> None:
    """A warning (an error under -W) for a public module that no capability page lists."""
    from sphinx.util import logging

    listed = set()
    for page in (HERE / "api").glob("*.rst"):
        listed |= {ln.strip() for ln in page.read_text().splitlines() if ln.startswith("   imunav")}
    missing = sorted(_public_modules() - listed - {"imunav", "imunav.cli"} - {
        m for m in _public_modules() if m.startswith("imunav.cli.")})
    for m in missing:
        logging.getLogger(__name__).warning(f"module {m} is on no page of docs/api/: add it to the autosummary "
                                            "list of its capability")


def setup(app):  # noqa: D103 - Sphinx hook
    from gallery import write_gallery_page

    app.connect("autodoc-process-docstring", _plain_bars, priority=600)
    app.connect("builder-inited", _check_every_module_listed)
    write_gallery_page(HERE / "_generated")
