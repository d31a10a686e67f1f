"""The air-data figures render from results (no computation in plot code)."""

import matplotlib

matplotlib.use("Agg")

from imunav.airdata import plot as P  # noqa: E402
from imunav.airdata.filter import run_thesis_filter  # noqa: E402
from imunav.airdata.scenario import ThesisScenario, simulate_thesis  # noqa: E402
from imunav.filters import detect_faults  # noqa: E402


def test_figures_render(tmp_path):
    d = simulate_thesis(ThesisScenario(kind="variance"), rng=0)
    r = run_thesis_filter(d.z, robust="gate")
    det = detect_faults(r.normalized, 20, start=d.scenario.onset_row)
    for name, fig in (("wind", P.plot_wind(r, d)), ("innov", P.plot_innovations(r)), ("det", P.plot_detectors(det))):
        out = tmp_path / f"{name}.png"
        fig.savefig(out)
        assert out.stat().st_size > 5000
        assert len(fig.axes) >= 3
