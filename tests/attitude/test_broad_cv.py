"""AdaptiveMEKF on the shared BROAD trials: out of fold against vqf, and the shipped defaults from the protocol.

The figures README quotes come from ``benchmarks/bench_attitude_broad.py``; this test re-derives the two that the
issue accepts on (leave-one-trial-out mean <= 0.95 x vqf, no trial worse than vqf by more than 2 deg) on every run,
and checks that ``ADAPTIVE_DEFAULTS`` is what the tuning procedure chooses on these trials, so that a hand-edited
default cannot pass for a tuned one.
"""

from dataclasses import replace

import numpy as np
import pytest
from broad_peers import vqf_errors
from shared_data import data_path

from imunav.attitude.adaptive import ADAPTIVE_DEFAULTS, ADAPTIVE_GRID
from imunav.attitude.benchmark import cv_grid_search
from imunav.io.broad import broad_trials

pytestmark = [pytest.mark.slow, pytest.mark.data]


def _vqf(files):
    return np.array([e.total_rmse_deg for e in vqf_errors(files, "9D")])


def test_adaptive_out_of_fold_beats_vqf_and_defaults_come_from_the_grid():
    files = broad_trials(data_path("broad"))
    assert len(files) == 10
    cv, res = cv_grid_search("adaptive", ADAPTIVE_GRID, files, workers=1)
    v = _vqf(files)
    ratio = cv.oof_mean / v.mean()
    print(f"\nadaptive leave-one-trial-out {cv.oof_mean:.3f} deg vs vqf {v.mean():.3f} deg: ratio {ratio:.3f} "
          f"(in sample {cv.in_sample_mean:.3f}); worst trial vs vqf {np.max(cv.oof - v):+.2f} deg")
    assert ratio <= 0.95
    assert np.max(cv.oof - v) <= 2.0
    # the out-of-fold figure is what the benchmark and README report (0.713 x when this was written)
    assert ratio == pytest.approx(0.713, abs=0.005)
    # the shipped defaults are the grid's in-sample choice
    assert replace(ADAPTIVE_DEFAULTS, **cv.in_sample_choice) == ADAPTIVE_DEFAULTS
    assert res[0].params == cv.in_sample_choice
