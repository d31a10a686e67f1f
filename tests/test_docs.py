"""The site builds with no warning (``make docs``: Sphinx, -W), so CI checks every docstring and guide page it
renders; and it works in a browser (issue 35, deliverable 3): no broken link or image on any page (checked on the
HTML; a link planted in a copy of the site must be reported), the search finds a command name, and, where Chromium
is installed (``make test`` installs it), every page opens without a console error and the first figure of each
guide page renders to a non-blank screenshot.  The site is built once for the module (about two minutes with the
gallery's short lab run).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from html import unescape
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

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


# one worker builds the site once for the module (two workers built it twice: a minute of CI)
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("docs")]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> tuple[Path, str]:
    """The built site (its html folder) and Sphinx's standard error."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    tmp_path = tmp_path_factory.mktemp("site")
    src = tmp_path / "docs"
    shutil.copytree(ROOT / "docs", src, ignore=shutil.ignore_patterns("_build", "_generated", "generated"))
    shutil.copy(ROOT / "CHANGELOG.md", tmp_path / "CHANGELOG.md")  # docs/changelog.md includes ../CHANGELOG.md
    (tmp_path / "lab.toml").write_text(TINY_LAB)
    env = {**os.environ, "IMUNAV_GALLERY_LAB": str(tmp_path / "lab.toml"),
           "PYTHONPATH": os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)}
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-q", str(src),
                        str(tmp_path / "html")], capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 0, r.stderr[-6000:]
    return tmp_path / "html", r.stderr


def test_docs_build_without_warnings(site):
    html, stderr = site
    assert "WARNING" not in stderr and "ERROR" not in stderr, stderr[-6000:]
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


# -- links, images, search, browser ------------------------------------------------------------------------------------


class _Refs(HTMLParser):
    """The ``href`` of every link, the ``src`` of every image and every element ``id`` of one page."""

    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.images: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "a" and a.get("href"):
            self.links.append(a["href"])
        elif tag == "img" and a.get("src"):
            self.images.append(a["src"])


def _refs(page: Path) -> _Refs:
    p = _Refs()
    p.feed(page.read_text(encoding="utf-8", errors="replace"))
    return p


def broken_refs(html: Path) -> list[str]:
    """Every local link whose file (or ``#anchor``) is missing and every image that is missing or empty, over all
    pages of a built site; links to other sites are not followed (the tests run offline)."""
    pages = {p: _refs(p) for p in html.rglob("*.html")}
    bad = []
    for page, refs in pages.items():
        where = page.relative_to(html)
        for kind, targets in (("link", refs.links), ("image", refs.images)):
            for ref in targets:
                u = urlsplit(ref)
                if u.scheme or u.netloc or ref.startswith(("mailto:", "javascript:", "data:")):
                    continue
                target = (page.parent / unquote(u.path)).resolve() if u.path else page
                if target.is_dir():
                    target = target / "index.html"
                if not target.is_file() or (kind == "image" and target.stat().st_size == 0):
                    bad.append(f"{where}: {kind} {ref} ({target.name} missing or empty)")
                elif kind == "link" and u.fragment and target.suffix == ".html":
                    ids = pages[target].ids if target in pages else _refs(target).ids
                    if unquote(u.fragment) not in ids:
                        bad.append(f"{where}: link {ref} (no #{u.fragment} in {target.name})")
    return bad


def test_no_broken_link_or_image(site):
    html, _ = site
    assert len(list(html.rglob("*.html"))) > 20
    assert broken_refs(html) == []


def test_a_planted_broken_link_and_image_are_reported(site, tmp_path):
    html, _ = site
    copy = tmp_path / "html"
    shutil.copytree(html, copy)
    page = copy / "guide" / "noise.html"
    text = page.read_text(encoding="utf-8")
    page.write_text(text.replace("</body>", '<a href="../nowhere.html">x</a><a href="gins.html#no-such-section">y</a>'
                                 '<img src="figures/missing.png"></body>'), encoding="utf-8")
    bad = broken_refs(copy)
    assert len(bad) == 3, bad
    assert any("nowhere.html" in b for b in bad) and any("no-such-section" in b for b in bad)
    assert any("missing.png" in b for b in bad)


def test_search_index_holds_the_command_names(site):
    """Sphinx's search runs in the browser over ``searchindex.js``: each command name must be a term of it."""
    html, _ = site
    index = (html / "searchindex.js").read_text(encoding="utf-8")
    for word in ("gins", "allan", "calibrate", "zupt", "airdata", "outage"):
        assert f'"{word}"' in index, word


def _chromium() -> str:
    import browser

    return browser.chromium()


def _console_errors(lines: list[str]) -> list[str]:
    return [ln for ln in lines if "error" in ln.lower() or "failed" in ln.lower() or "uncaught" in ln.lower()]


def test_every_page_opens_in_chromium_without_console_error(site, tmp_path):
    """Every page of the site is opened in headless Chromium (in frames of a few harness pages, one browser each):
    a script error, a resource that fails to load or any other console error fails the test."""
    import browser

    _chromium()
    html, _ = site
    pages = sorted(html.rglob("*.html"))
    # a planted page with a script error, in the first harness: the harness must report it (and only it)
    planted = html / "_planted_error.html"
    planted.write_text("<html><body><script>plantedUndefinedFunction();</script></body></html>", encoding="utf-8")
    errors = []
    try:
        for i in range(0, len(pages), 40):
            harness = html / f"_harness_{i}.html"
            frames = "".join(f'<iframe src="{p.relative_to(html).as_posix()}" width="800" height="600"></iframe>'
                             for p in ([planted] if i == 0 else []) + pages[i:i + 40])
            harness.write_text(f"<!DOCTYPE html><html><body>{frames}</body></html>", encoding="utf-8")
            try:
                errors += _console_errors(browser.render(harness, tmp_path / f"h{i}.png", width=1600, height=1200))
            finally:
                harness.unlink()
    finally:
        planted.unlink()
    assert any("plantedUndefinedFunction" in e for e in errors), "the harness missed the planted script error"
    errors = [e for e in errors if "plantedUndefinedFunction" not in e]
    assert errors == [], errors[:20]


def test_search_page_finds_a_command_name_in_chromium(site):
    exe = _chromium()
    html, _ = site
    url = (html / "search.html").resolve().as_uri() + "?q=outage"
    import tempfile

    with tempfile.TemporaryDirectory() as profile:
        r = subprocess.run([exe, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                            f"--user-data-dir={profile}", "--virtual-time-budget=15000", "--dump-dom", url],
                           capture_output=True, text=True, timeout=120)
    found = re.findall(r'<a[^>]+href="([^"]*guide/gins[^"]*)"', r.stdout)
    assert found, r.stdout[-3000:]


def test_first_figure_of_each_guide_page_renders(site, tmp_path):
    """The first image of each guide page that has one, alone on a page of its own, renders to a non-blank
    screenshot (the file is a picture a browser can draw, not only a file that exists)."""
    import browser

    _chromium()
    html, _ = site
    shown = 0
    for page in sorted((html / "guide").glob("*.html")):
        images = _refs(page).images
        if not images:
            continue
        img = (page.parent / unquote(urlsplit(images[0]).path)).resolve()
        wrapper = tmp_path / f"{page.stem}.html"
        wrapper.write_text(f'<!DOCTYPE html><html><body style="margin:0"><img src="{img.as_uri()}"></body></html>',
                           encoding="utf-8")
        png = tmp_path / f"{page.stem}.png"
        console = browser.render(wrapper, png, width=900, height=700)
        assert _console_errors(console) == [], (page.name, console)
        browser.assert_not_blank(png)
        shown += 1
    assert shown >= 2
