"""Every writer gives its output the usual mode (0666 minus the umask), not mkstemp's 0600 (issue 16, item 7:
`noise --yaml` / `--json` and `attitude montecarlo --plot` wrote 0600 through their own temp-file code)."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest
from builders import static_imu
from cli_contract import invoke

from imunav.io import write_imu


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    try:
        yield 0o644
    finally:
        os.umask(old)


def _mode(path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_noise_fit_json_and_kalibr_yaml_modes(tmp_path, umask_022):
    from imunav.noise import allan_deviation, fit_noise, write_kalibr_yaml

    rng = np.random.default_rng(0)
    gyro = fit_noise(allan_deviation(rng.normal(0, 0.01, (20_000, 3)), fs=100.0, units="rad/s"), terms=("N", "K"))
    accel = fit_noise(allan_deviation(rng.normal(0, 0.02, (20_000, 3)), fs=100.0, units="m/s^2"), terms=("N", "K"))
    assert _mode(gyro.to_json(tmp_path / "fit.json")) == umask_022
    assert _mode(write_kalibr_yaml(tmp_path / "imu.yaml", gyro, accel, 100.0)) == umask_022
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fit.json", "imu.yaml"]  # no temp file left


def test_attitude_figure_mode(tmp_path, umask_022):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from imunav.attitude.plot import save

    fig = plt.figure()
    try:
        out = save(fig, tmp_path / "mc.png")
    finally:
        plt.close(fig)
    assert _mode(out) == umask_022
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["mc.png"]


def test_json_and_figure_outputs_follow_the_umask(tmp_path):
    """--plot / --yaml / --json files were created 0600 by mkstemp; they must get 0666 & ~umask like the rest."""
    old = os.umask(0o022)
    try:
        write_imu(static_imu(3000), tmp_path / "st.csv")
        assert invoke("noise", tmp_path / "st.csv", "--terms", "N,K", "--yaml", tmp_path / "imu.yaml",
                    "--json", tmp_path / "n.json").exit_code == 0
        assert invoke("airdata", "simulate", "cruise", "--duration", "20", "--out", tmp_path / "a.npz",
                    "--json", tmp_path / "as.json").exit_code == 0
        assert invoke("airdata", "run", tmp_path / "a.npz", "--plot", tmp_path / "ar.png",
                    "--json", tmp_path / "ar.json").exit_code == 0
        import matplotlib

        from imunav.attitude.plot import save

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        save(plt.figure(), tmp_path / "fig.png")
    finally:
        os.umask(old)
    modes = {p.name: p.stat().st_mode & 0o777 for p in tmp_path.iterdir()}
    assert set(modes.values()) == {0o644}, modes
