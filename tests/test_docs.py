"""The reference site builds with no warning (``make docs``: Sphinx, -W), so CI checks every docstring it renders."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from html import unescape
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

TINY_LAB = """
[lab]
seed = 3
steps = ["simulate_tests"]

[simulate_tests]
fs = 10.0
dwell_s = 1.0
transition_s = 0.5
remount_s = 1.0
static_duration_s = 20.0
"""


@pytest.mark.slow
def test_docs_build_without_warnings(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    src = tmp_path / "docs"
    shutil.copytree(ROOT / "docs", src, ignore=shutil.ignore_patterns("_build", "_generated", "generated"))
    shutil.copy(ROOT / "CHANGELOG.md", tmp_path / "CHANGELOG.md")  # docs/changelog.md includes ../CHANGELOG.md
    (tmp_path / "lab.toml").write_text(TINY_LAB)
    env = {**os.environ, "IMUNAV_GALLERY_LAB": str(tmp_path / "lab.toml"),
           "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)}
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-q", str(src),
                        str(tmp_path / "html")], capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 0, r.stderr[-6000:]
    assert "WARNING" not in r.stderr and "ERROR" not in r.stderr, r.stderr[-6000:]
    html = tmp_path / "html"
    guide = sorted(p.stem for p in (ROOT / "docs" / "guide").glob("*.md"))
    assert {"noise", "calibrate", "attitude", "zupt", "gins", "airdata", "lab", "files", "howto", "python"} <= set(guide)
    for page in (*(f"guide/{g}.html" for g in guide), "changelog.html"):
        assert (html / page).is_file(), page
    for page in ("index.html", "conventions.html", "gallery.html", "api/io.html",
                 "api/generated/imunav.io.px4params.html", "api/generated/imunav.noise.fit.html"):
        assert (html / page).is_file(), page
    # the gallery shows the lab's figures; the API pages hold the numpydoc sections
    assert (html / "gallery.html").read_text().count("<img") >= 3
    assert "write_px4_params" in (html / "api/generated/imunav.io.px4params.html").read_text()
    # no raw markup reaches a reader: roles and double backticks that reST did not render (a role in a numpydoc
    # section it does not parse, inline literals glued to a sign)
    raw = {}
    for page in html.rglob("*.html"):
        text = re.sub(r"<[^>]+>", "", re.sub(r"<(script|style)[^>]*>.*?</\1>", "", page.read_text(errors="ignore"),
                                             flags=re.S))
        found = [m for m in (":func:`", ":class:`", ":meth:`", ":mod:`", ":data:`", ":attr:`", "``")
                 if m in unescape(text)]
        if found:
            raw[str(page.relative_to(html))] = found
    assert raw == {}, raw
