"""Monte Carlo engine: seeding, executors, gathering, consistency."""

from __future__ import annotations

import mc_scenarios as sc
import numpy as np
import pytest

from imunav.errors import InvalidInputError
from imunav.filters import ConsistencyResult, consistency_test
from imunav.lab.montecarlo import run_batch, run_montecarlo, spawn_generators


def test_same_seed_same_numbers_whatever_the_chunking():
    a = run_montecarlo(sc.random_walk_kf, 12, seed=7, executor="serial", chunk_size=5)
    b = run_montecarlo(sc.random_walk_kf, 12, seed=7, executor="serial", chunk_size=1)
    np.testing.assert_array_equal(a.metrics["rmse"], b.metrics["rmse"])
    np.testing.assert_array_equal(a.arrays["nees"], b.arrays["nees"])
    c = run_montecarlo(sc.random_walk_kf, 12, seed=8, executor="serial")
    assert not np.array_equal(a.metrics["rmse"], c.metrics["rmse"])


def test_run_i_is_reproducible_alone():
    g_all = spawn_generators(3, 5)
    g_4 = spawn_generators(3, 1, start=4)[0]
    assert g_all[4].normal() == g_4.normal()


def test_processes_equal_serial():
    a = run_montecarlo(sc.random_walk_kf, 8, seed=1, executor="serial")
    b = run_montecarlo(sc.random_walk_kf, 8, seed=1, executor="processes", n_workers=2, chunk_size=3)
    np.testing.assert_array_equal(a.arrays["nees"], b.arrays["nees"])


def test_dask_local_cluster_equals_local():
    pytest.importorskip("dask.distributed")
    a = run_montecarlo(sc.random_walk_kf, 10, seed=11, executor="serial")
    b = run_montecarlo(sc.random_walk_kf, 10, seed=11, executor="dask", n_workers=2, chunk_size=2)
    np.testing.assert_array_equal(a.arrays["nees"], b.arrays["nees"])
    np.testing.assert_array_equal(a.metrics.to_numpy(), b.metrics.to_numpy())


def test_batched_scenario():
    r = run_montecarlo(sc.batched_mean, 400, seed=2, executor="serial", batched=True, chunk_size=64)
    # mean of 1000 N(0,1) has sd 1/sqrt(1000); over 400 runs the sd estimate is within ~3.5 sigma of it
    sd = r.metrics["mean"].std(ddof=1)
    assert abs(sd - 1 / np.sqrt(1000)) < 3.5 * (1 / np.sqrt(1000)) / np.sqrt(2 * 399)
    s = r.summary()
    assert set(["mean", "std", "p5", "p50", "p95"]) <= set(s.index)


def test_optimal_kf_is_nees_consistent():
    r = run_montecarlo(sc.random_walk_kf, 50, seed=5, executor="serial")
    c = r.consistency("nees", dof=1)
    assert isinstance(c, ConsistencyResult)  # the one consistency result of imunav.filters
    # The KF is optimal, so its average NEES lies in the 95 % band about 95 % of the time.
    assert c.fraction_inside > 0.85
    assert c.lower < 1.0 < c.upper


def test_inconsistent_filter_is_flagged():
    bad = consistency_test(np.full((50, 100), 3.0), dof=1)
    assert bad.fraction_inside == 0.0


def test_batch_keeps_order_and_reports_failures():
    out = run_batch(sc.failing, [0, 1, 2, 3], executor="processes", n_workers=2)
    assert out[0] == {"x": 0} and out[3] == {"x": 6}
    assert isinstance(out[2], ValueError) and "unit 2" in str(out[2])


def test_bad_arguments():
    with pytest.raises(InvalidInputError, match="n_runs"):
        run_montecarlo(sc.random_walk_kf, 0)
    with pytest.raises(InvalidInputError, match="executor"):
        run_montecarlo(sc.random_walk_kf, 2, executor="cloud")
    with pytest.raises(InvalidInputError, match="dof"):
        consistency_test(np.ones((2, 2)), 0)


def test_attitude_paper_seed_words_follow_the_documented_scheme():
    # seeding="seed_word" (the lab's Table 2): run i simulates with default_rng(w_i), w_i the first 32-bit word of
    # child i of SeedSequence(seed) as numpy's own spawn() makes it; equal to running those generators directly
    from imunav.scenarios import attitude_paper, paper_rmse, paper_table

    kw = {"filters": ("proposed", "lee"), "duration": 5.0}
    r = run_montecarlo(attitude_paper, 3, seed=4, executor="serial", batched=True, seeding="seed_word", **kw)
    words = [int(s.generate_state(1)[0]) for s in np.random.SeedSequence(4).spawn(3)]
    direct = attitude_paper([np.random.default_rng(w) for w in words], **kw)
    rmse = paper_rmse(r)
    assert list(rmse) == ["proposed", "lee"] and rmse["lee"].shape == (3, 2)
    for i, row in enumerate(direct):
        assert rmse["lee"][i].tolist() == [row["lee_pitch_rmse_deg"], row["lee_roll_rmse_deg"]]
    assert paper_table(r)["proposed"]["pitch_mean"] == pytest.approx(np.mean(rmse["proposed"][:, 0]), rel=1e-15)
    g = run_montecarlo(attitude_paper, 3, seed=4, executor="serial", batched=True, **kw)
    assert not np.array_equal(paper_rmse(g)["lee"], rmse["lee"])  # the generator seeding is another stream
