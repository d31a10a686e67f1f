"""HTML report builder."""

from __future__ import annotations

import re

from imunav.lab.report import Parameter, Report


def test_report_is_self_contained(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = Report("Lab <test>", "seed 0")
    s = r.section("Noise", passed=True)
    s.text("Allan deviation & fit")
    fig, ax = plt.subplots()
    ax.loglog([1, 10], [1, 0.3])
    s.figure(fig, "ADEV")
    s.table([{"axis": "x", "N": 1.2e-4}, {"axis": "y", "N": 1.3e-4}], caption="terms")
    s.parameters([Parameter("bias x", 0.1, 0.01, "deg/h", truth=0.105, limit="≤ 1 deg/h", passed=True)])
    r.section("Calibration", passed=False)
    out = r.write(tmp_path / "report.html")
    text = out.read_text()
    assert text.startswith("<!DOCTYPE html>")
    assert "Lab &lt;test&gt;" in text  # escaped
    assert "data:image/png;base64," in text
    assert "<script" not in text and "http://" not in text and "https://" not in text
    assert text.count("badge fail") >= 2  # section + overall verdict
    assert re.search(r"<td>-0\.5</td>", text)  # (0.1 - 0.105) / 0.01 error in sigma
    assert r.passed is False
