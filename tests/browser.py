"""Headless Chromium rendering for report tests (skips when Chromium is absent)."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    pytest.skip("Chromium not installed (make test installs Debian's chromium when it can)")


def render(html_file: Path, png: Path, width: int = 1200, height: int = 3000) -> list[str]:
    """Screenshot ``html_file`` into ``png``; return the browser console messages."""
    exe = chromium()
    with tempfile.TemporaryDirectory() as profile:
        proc = subprocess.run(
            [
                exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                f"--user-data-dir={profile}", "--enable-logging=stderr", "--v=0",
                f"--window-size={width},{height}", f"--screenshot={png}", html_file.resolve().as_uri(),
            ],
            capture_output=True, text=True, timeout=120,
        )
    if not png.exists():
        raise AssertionError(f"Chromium wrote no screenshot (exit {proc.returncode}): {proc.stderr[-2000:]}")
    return [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]


def assert_not_blank(png: Path) -> None:
    import matplotlib.image as mpimg

    img = mpimg.imread(png)
    assert img.std() > 0.01, "the screenshot is blank"
