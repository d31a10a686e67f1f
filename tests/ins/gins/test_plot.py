"""GNSS/INS figures (imunav.ins.gins.plot): long runs are drawn thinned, their ends kept."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.earth import lla_to_ned
from imunav.ins.gins.plot import MAX_POINTS, plot_track
from imunav.io.kfgins import NavTrack


def test_a_long_track_is_drawn_with_at_most_max_points_and_its_ends():
    """A one-hour track at 200 Hz: the GNSS/INS line holds at most MAX_POINTS + 1 points, evenly spaced, from the
    first sample to the last; a short track is drawn whole."""
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    for n, whole in ((720_001, False), (5_000, True)):
        t = np.arange(n) / 200.0
        lla = np.column_stack([0.8 + 1e-7 * np.sin(t / 60), 0.2 + 1e-7 * np.cos(t / 60), np.full(n, 100.0)])
        nav = NavTrack(t, lla, np.zeros((n, 3)), np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)), 0)
        fig = plot_track(nav)
        line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "GNSS/INS")
        x = line.get_xdata()
        assert (x.size == n) if whole else (x.size <= MAX_POINTS + 1 and x.size >= MAX_POINTS // 2)
        np.testing.assert_allclose(x[[0, -1]], lla_to_ned(lla[[0, -1]], lla[0])[:, 1], rtol=0, atol=1e-9)
        plt.close(fig)
