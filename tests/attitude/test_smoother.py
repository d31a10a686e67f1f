"""The smoother's own defaults: what they are made of, and what they fix on real recordings.

``SMOOTHER_DEFAULTS`` are the real-time filter's defaults with only the parameters of ``SMOOTHER_GRID`` changed
(the grid the leave-one-trial-out tuning searches, ``benchmarks/bench_attitude_broad.py``).  With the real-time
filter's 10 % / 10° field-disturbance test the smoother was *worse* than the forward filter it smooths on BROAD
translation and stationary-magnet trials (total RMSE 1.79° vs 1.28° on trial 10, 2.98° vs 1.89° on trial 30): the
field is distorted by a few per cent and degrees along the path, the test lets it through, and the backward pass
fits it from both sides.  The data test checks that this no longer happens.
"""

from dataclasses import fields

import pytest
from shared_data import data_path

from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS, AdaptiveMEKF
from imunav.attitude.metrics import attitude_rmse
from imunav.attitude.smoother import SMOOTHER_DEFAULTS, SMOOTHER_GRID, Smoother
from imunav.io.broad import broad_trials, load_broad


def test_smoother_defaults_are_the_realtime_ones_but_for_the_grid():
    changed = {f.name for f in fields(SMOOTHER_DEFAULTS)
               if getattr(SMOOTHER_DEFAULTS, f.name) != getattr(ADAPTIVE_DEFAULTS, f.name)}
    assert changed <= set(SMOOTHER_GRID)
    assert changed  # the smoother is tuned for the offline problem, not a copy of the real-time filter
    for k, values in SMOOTHER_GRID.items():
        assert getattr(SMOOTHER_DEFAULTS, k) in values, k
    assert Smoother().config == SMOOTHER_DEFAULTS


@pytest.mark.slow
@pytest.mark.data
@pytest.mark.parametrize("trial", ["10_undisturbed_slow_translation_A", "30_disturbed_stationary_magnet_C"])
def test_smoother_beats_the_forward_filter_on_a_mildly_distorted_field(trial):
    files = [f for f in broad_trials(data_path("broad")) if f.stem == trial]
    assert files, f"trial {trial} missing from the shared BROAD data"
    tr = load_broad(files[0])
    fwd = attitude_rmse(AdaptiveMEKF().run(tr.imu).q_nb, tr.q_ref_nb, tr.movement)
    smo = attitude_rmse(Smoother().run(tr.imu).q_nb, tr.q_ref_nb, tr.movement)
    print(f"\n{trial}: forward {fwd.total_rmse_deg:.2f} deg (heading {fwd.heading_rmse_deg:.2f}), "
          f"smoother {smo.total_rmse_deg:.2f} deg (heading {smo.heading_rmse_deg:.2f})")
    # a smoother sees the filter's information and more: it must not lose to it (before SMOOTHER_DEFAULTS it lost
    # by 0.5 deg on trial 10 and 1.1 deg on trial 30).  Deterministic runs: no statistical margin is needed.
    assert smo.total_rmse_deg < fwd.total_rmse_deg
    # heading: since issue 34 the smoother's forward pass is not the real-time filter (1 s accelerometer low-pass,
    # 6 s tilt correction, bias random walk 2e-4): on trial 30 its heading is 1.21 deg against the forward filter's
    # 1.18 (total 1.56 against 1.89); it must not lose by more than that
    assert smo.heading_rmse_deg < fwd.heading_rmse_deg + 0.05
