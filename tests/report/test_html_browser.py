"""The HTML report renders in headless Chromium without console errors."""

from __future__ import annotations

import browser

from imunav.lab.report import Parameter, Report


def test_report_renders_in_chromium(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    browser.chromium()
    r = Report("Render check")
    s = r.section("Figures", passed=True)
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    s.figure(fig, "line")
    s.parameters([Parameter("x", 1.0, 0.1, "m", passed=True)])
    page = r.write(tmp_path / "r.html")
    console = browser.render(page, tmp_path / "r.png")
    assert console == [], console
    browser.assert_not_blank(tmp_path / "r.png")
