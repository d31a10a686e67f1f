"""What the filter rejected and when (issue 34, deliverable 4): the summary line and the figure.

Oracle: a recording with a field disturbance and an acceleration bump at known times (builders.disturbed_imu);
the flagged intervals must be those, to within the filter's detection delay.
"""

import json

import numpy as np
import pytest
from builders import DISTURBED_ACCEL_S, DISTURBED_FIELD_S, disturbed_imu

from imunav.attitude.mahony import Mahony
from imunav.attitude.mekf import MEKF, MekfConfig
from imunav.attitude.metrics import error_angles
from imunav.attitude.plot import plot_rejections, save
from imunav.attitude.rejections import rejected_intervals, rejection_summary
from imunav.errors import InvalidInputError, ShapeError

CFG = MekfConfig(accel_reject_threshold=0.03, mag_norm_threshold=0.1, mag_dip_threshold=0.2,
                 rest_gyro_threshold=0.05, rest_accel_threshold=0.3)


@pytest.fixture(scope="module")
def run():
    data, q_true = disturbed_imu()
    r = MEKF(CFG).run(data)
    return r, error_angles(r.q_nb, q_true)


def test_intervals_are_the_disturbances(run):
    r, _ = run
    dt = r.t[1] - r.t[0]
    (m,) = rejected_intervals(r.t, r.flags["mag_disturbed"])
    (a,) = rejected_intervals(r.t, r.flags["acc_rejected"])
    # the field test has no low-pass here: each edge within a sample of the disturbance's
    assert m == pytest.approx(DISTURBED_FIELD_S, abs=1.5 * dt)
    assert a == pytest.approx(DISTURBED_ACCEL_S, abs=1.5 * dt)


def test_summary_line_says_what_when_and_the_error(run):
    r, ang = run
    s = rejection_summary(r, ang, name="disturbed")
    assert s.mag_intervals == 1 and s.acc_intervals == 1
    assert s.mag_longest_s == pytest.approx(np.diff(DISTURBED_FIELD_S)[0], abs=0.02)
    assert s.mag_rejected_fraction == pytest.approx(3.0 / 40.0, abs=0.001)
    assert s.acc_rejected_fraction == pytest.approx(1.0 / 40.0, abs=0.001)
    assert s.rest_fraction > 0.15  # 10 s at rest, after the 1 s rest time
    assert s.error_mag_rejected_deg is not None and s.error_mag_used_deg is not None
    line = s.line()
    assert line.startswith("disturbed: field rejected 7.5 % of 40 s in 1 intervals (longest 3.0 s)")
    assert "accelerometer rejected 2.5 % in 1 intervals" in line
    json.dumps(s.to_dict(), allow_nan=False)


def test_summary_needs_flags_and_matching_angles(run):
    r, ang = run
    data, _ = disturbed_imu()
    with pytest.raises(InvalidInputError, match="no rejection flags"):
        rejection_summary(Mahony().run(data))
    with pytest.raises(ShapeError, match="error_angles"):
        rejection_summary(r, error_angles(r.q_nb[:10], r.q_nb[:10]))
    six = MEKF(CFG).run(data, use_mag=False)
    s = rejection_summary(six)
    assert s.mag_rejected_fraction is None and "field rejected n/a" in s.line()


def test_figure(run, tmp_path):
    r, ang = run
    fig = plot_rejections(r, ang, title=rejection_summary(r, ang).line())
    assert len(fig.axes) == 2
    assert len(fig.axes[1].get_yticklabels()) == 3
    p = save(fig, tmp_path / "rej.png")
    assert p.stat().st_size > 1000
    assert len(plot_rejections(r).axes) == 1
