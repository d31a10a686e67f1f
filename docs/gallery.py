"""The documentation gallery: the figures a lab run makes, on one page.

``python docs/gallery.py [OUT]`` (and the Sphinx build, through ``conf.py``) runs the lab of
``gallery_lab.toml`` (or the TOML named by ``$IMUNAV_GALLERY_LAB``) into ``OUT/lab`` (default
``docs/_generated``) unless a finished run is already there,
and writes ``OUT/gallery.md``: each step's title and its figures.  Delete the folder to run the lab again.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def write_gallery_page(out: str | Path) -> Path:
    """Run the gallery lab into ``out/lab`` if needed and write ``out/gallery.md``; returns the page path.

    Parameters
    ----------
    out : path-like
        Folder of the generated files (inside the Sphinx source folder when the page is built).

    Returns
    -------
    Path
        The Markdown page.
    """
    from imunav.lab.runner import run_lab

    out = Path(out)
    report = out / "lab"
    if not (report / "summary.json").is_file():
        # IMUNAV_GALLERY_LAB: another lab definition (the docs test uses a tiny one to stay quick)
        config = os.environ.get("IMUNAV_GALLERY_LAB") or HERE / "gallery_lab.toml"
        run_lab(report, config, progress=False, overwrite=True)  # a killed earlier run is cleared
    summary = json.loads((report / "summary.json").read_text())
    figs = sorted((report / "figures").glob("*.png"))
    lines = ["# Gallery of the lab's figures", "",
             "Made by `imunav lab` on the built-in virtual IMU (a shortened run, `docs/gallery_lab.toml`; "
             "`imunav lab --out lab-report` makes them at full length, with the HTML report around them).", ""]
    used: set[Path] = set()
    for step in summary["steps"]:
        mine = [f for f in figs if f not in used and (f.stem.startswith(step["name"])
                                                      or f.stem in _step_figures(step))]
        if not mine:
            continue
        lines += [f"## {step['title']}", ""]
        for f in mine:
            used.add(f)
            lines += [f"![{f.stem}](lab/figures/{f.name})", "", f"*{f.stem.replace('_', ' ')}*", ""]
    rest = [f for f in figs if f not in used]
    if rest:
        lines += ["## Other figures", ""]
        for f in rest:
            lines += [f"![{f.stem}](lab/figures/{f.name})", "", f"*{f.stem.replace('_', ' ')}*", ""]
    page = out / "gallery.md"
    text = "\n".join(lines) + "\n"
    if not page.is_file() or page.read_text() != text:  # unchanged page: Sphinx keeps its cache
        page.write_text(text)
    return page


def _step_figures(step: dict) -> set[str]:
    """Figure names a step lists in its summary (the simulated tests name theirs after the test)."""
    tests = (step.get("summary") or {}).get("tests") or {}
    return set(tests) if isinstance(tests, dict) else set()


if __name__ == "__main__":
    print(write_gallery_page(sys.argv[1] if len(sys.argv) > 1 else HERE / "_generated"))
