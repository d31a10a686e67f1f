"""imunav.ins.gins.plot: long series are drawn by their envelope, not sample by sample."""

from __future__ import annotations

import numpy as np
import pytest

from imunav import earth
from imunav.io.kfgins import NavTrack

pytest.importorskip("matplotlib")


def test_a_long_track_is_drawn_by_its_extremes():
    """A 200,000-sample track: the drawn line keeps a few thousand samples, among them the first, the last and
    the extreme east / north of the whole track (the figure's extent and shape are those of every sample)."""
    import matplotlib.pyplot as plt

    from imunav.ins.gins.plot import plot_track

    n = 200_000
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 2 * np.pi, n)
    ned = np.column_stack([500 * np.sin(s) + rng.normal(0, 0.5, n), 300 * np.sin(2 * s), np.zeros(n)])
    ned[123_457, 1] += 40.0  # a one-sample spike: a stride would miss it
    origin = np.array([np.radians(30.0), np.radians(114.0), 20.0])
    lla = earth.ned_to_lla(ned, origin)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    fig = plot_track(NavTrack(np.arange(n) / 100.0, lla, np.zeros((n, 3)), q))
    try:
        line = next(ln for ln in fig.axes[0].lines if ln.get_label() == "GNSS/INS")
        x, y = line.get_xdata(), line.get_ydata()
        p = earth.lla_to_ned(lla, lla[0])
        assert 2000 < x.size <= 4 * 2000 + 100
        assert (x[0], y[0], x[-1], y[-1]) == (p[0, 1], p[0, 0], p[-1, 1], p[-1, 0])
        assert (x.min(), x.max(), y.min(), y.max()) == (p[:, 1].min(), p[:, 1].max(), p[:, 0].min(), p[:, 0].max())
    finally:
        plt.close(fig)
