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


def test_fixed_margins_hold_every_label():
    """The figures place their axes at fixed margins (no tight_layout, which draws a figure twice): on a short
    21-state run with a truth, every panel with its tick labels, axis labels and title lies inside the figure,
    clear of the other panels and of the figure's title."""
    import matplotlib.pyplot as plt

    from imunav.ins.gins import GinsConfig, GinsFilter
    from imunav.ins.gins.plot import plot_errors, plot_imu_errors, plot_track
    from imunav.sim import presets, simulate_imu
    from imunav.sim.gnss import simulate_gnss
    from imunav.sim.vehicle import demo_drive, vehicle_trajectory

    truth = vehicle_trajectory(demo_drive(120), fs=50, origin_lla=(np.radians(30.44), np.radians(114.47), 20.0))
    imu = simulate_imu(truth, presets.get("mems_adis16465"), rng=1)
    gnss = simulate_gnss(truth, rng=2)
    res = GinsFilter(GinsConfig.from_preset("mems_adis16465")).run(
        imu, gnss, lla0=truth.pos_lla[0], vel0=truth.vel_ned[0], q0=truth.q_nb[0])
    ref = NavTrack(truth.t, truth.pos_lla, truth.vel_ned, truth.q_nb)
    for fig in (plot_errors(res, ref), plot_imu_errors(res), plot_track(res, gnss, ref)):
        try:
            fig.canvas.draw()
            r = fig.canvas.get_renderer()
            boxes = [ax.get_tightbbox(r) for ax in fig.axes]
            assert len(boxes) in (1, 9, 12)
            for i, b in enumerate(boxes):
                assert b.x0 >= 0 and b.y0 >= 0 and b.x1 <= fig.bbox.width and b.y1 <= fig.bbox.height, (i, b)
                assert not any(b.overlaps(o) for o in boxes[i + 1:]), i
                if fig._suptitle is not None:
                    assert not b.overlaps(fig._suptitle.get_window_extent(r)), i
        finally:
            plt.close(fig)
