"""Allan family: NIST NBS14 oracles, Stable32 bounds, closed forms, peers, bad input."""

from __future__ import annotations

import numpy as np
import pytest

from imunav.errors import InsufficientDataError, InvalidInputError, NonFiniteError, ShapeError
from imunav.noise import allan_deviation, tau_grid
from imunav.noise.edf import edf_greenhall

# NIST SP 1065 p.107, NBS14 10-point set (references.md §1)
NBS14_X = np.array([0, 103.11111, 123.22222, 157.33333, 166.44444, 48.55555, -96.33333, -2.22222, 111.88889, 0])
NBS14_Y = np.array([892, 809, 823, 798, 671, 644, 883, 903, 677.0])
NBS14_10 = {
    "standard": (91.22945, 115.8082),
    "overlapping": (91.22945, 85.95287),
    "modified": (91.22945, 74.78849),
    "total": (91.22945, 93.90379),
    "hadamard": (70.80608, 116.7980),
    "time": (52.67135, 86.35831),
    "overlapping_hadamard": (70.80607, 85.61487),
}
# NBS14 1000-point set (references.md §1), tau = 1, 10, 100
NBS14_1000 = {
    "standard": (2.922319e-01, 9.965736e-02, 3.897804e-02),
    "overlapping": (2.922319e-01, 9.159953e-02, 3.241343e-02),
    "modified": (2.922319e-01, 6.172376e-02, 2.170921e-02),
    "total": (2.922319e-01, 9.134743e-02, 3.406530e-02),
    "hadamard": (2.943883e-01, 1.052754e-01, 3.910860e-02),
    "time": (1.687202e-01, 3.563623e-01, 1.253382e00),
    "overlapping_hadamard": (2.943883e-01, 9.581083e-02, 3.237638e-02),
}


def nbs14_1000() -> np.ndarray:
    # the record is n0 .. n999 (n0 included), as the published values require
    n = 1234567890
    out = np.empty(1000)
    for i in range(1000):
        out[i] = n / 2147483647
        n = (16807 * n) % 2147483647
    return out


def test_nbs14_generator_check_values():
    n = 1234567890
    seq = []
    for _ in range(3):
        n = (16807 * n) % 2147483647
        seq.append(n)
    assert seq == [395529916, 1209410747, 633705974]


@pytest.mark.parametrize("kind", list(NBS14_10))
def test_nbs14_10_point_phase_and_frequency(kind):
    want = np.array(NBS14_10[kind])
    rp = allan_deviation(NBS14_X, 1.0, [1, 2], kind, input="phase")
    rf = allan_deviation(NBS14_Y, 1.0, [1, 2], kind, input="rate")
    np.testing.assert_allclose(rp.adev, want, rtol=1e-4)
    np.testing.assert_allclose(rf.adev, want, rtol=1e-4)


@pytest.mark.parametrize("kind", list(NBS14_1000))
def test_nbs14_1000_point_phase_and_frequency(kind):
    y = nbs14_1000()
    x = np.concatenate(([0.0], np.cumsum(y)))
    want = np.array(NBS14_1000[kind])
    rf = allan_deviation(y, 1.0, [1, 10, 100], kind)
    rp = allan_deviation(x, 1.0, [1, 10, 100], kind, input="phase")
    np.testing.assert_allclose(rf.adev, want, rtol=1e-4)
    np.testing.assert_allclose(rp.adev, want, rtol=1e-4)


def test_increment_input_equals_rate_input():
    y = nbs14_1000()
    r1 = allan_deviation(y, 4.0, "octave")
    r2 = allan_deviation(y / 4.0, 4.0, "octave", input="increment")
    np.testing.assert_allclose(r1.adev, r2.adev, rtol=1e-12)


def test_stable32_oadev_confidence_bounds():
    # Stable32 v1.60 octave OADEV of the NBS14 1000-point record with 68.3 % bounds (references.md §1)
    st = {1: (2.9223e-01, 2.8515e-01, 2.9987e-01), 2: (2.0102e-01, 1.9520e-01, 2.0738e-01),
          4: (1.4479e-01, 1.3931e-01, 1.5098e-01), 8: (1.0570e-01, 1.0038e-01, 1.1198e-01),
          16: (6.1915e-02, 5.7696e-02, 6.7217e-02), 32: (4.8082e-02, 4.3654e-02, 5.4202e-02),
          64: (3.6237e-02, 3.1755e-02, 4.3377e-02), 128: (2.7674e-02, 2.3045e-02, 3.7027e-02)}
    x = np.concatenate(([0.0], np.cumsum(nbs14_1000())))
    r = allan_deviation(x, 1.0, "octave", input="phase")
    for m, (d, lo, hi) in st.items():
        j = int(np.flatnonzero(r.m == m)[0])
        np.testing.assert_allclose(r.adev[j], d, rtol=2e-4)
        np.testing.assert_allclose(r.adev_lo[j], lo, rtol=1e-2)
        np.testing.assert_allclose(r.adev_hi[j], hi, rtol=1e-2)


def test_greenhall_edf_matches_allantools():
    ci = pytest.importorskip("allantools.ci")
    for alpha in (2, 1, 0, -1, -2):
        for m in (1, 3, 16, 100):
            for n in (1001, 40000):
                for ov, mod in ((True, False), (False, False), (True, True)):
                    if alpha == 2 and not mod and not ov and n // m < 5:
                        continue
                    want = ci.edf_greenhall(alpha=alpha, d=2, m=m, N=n, overlapping=ov, modified=mod)
                    assert edf_greenhall(alpha, 2, m, n, ov, mod) == pytest.approx(want, rel=1e-9)
                want = ci.edf_greenhall(alpha=alpha, d=3, m=m, N=n, overlapping=True, modified=False)
                assert edf_greenhall(alpha, 3, m, n, True, False) == pytest.approx(want, rel=1e-9)


@pytest.mark.parametrize("kind,fn", [("overlapping", "oadev"), ("standard", "adev"), ("modified", "mdev"),
                                     ("overlapping_hadamard", "ohdev"), ("hadamard", "hdev"),
                                     ("total", "totdev"), ("time", "tdev")])
def test_matches_allantools(kind, fn, rng):
    at = pytest.importorskip("allantools")
    y = rng.normal(size=20_000) + np.cumsum(rng.normal(scale=0.01, size=20_000))
    ms = np.array([1, 2, 3, 7, 16, 50, 333, 1000])
    r = allan_deviation(y, 10.0, ms / 10.0, kind)
    _, dev, _, _ = getattr(at, fn)(y, rate=10.0, data_type="freq", taus=ms / 10.0)
    np.testing.assert_allclose(r.adev, dev, rtol=1e-9)


def test_white_and_random_walk_closed_forms(rng):
    # AVAR = N^2/tau (white rate), K^2 tau/3 (random-walk rate); 5 % at tau where EDF is large
    fs, n = 100.0, 400_000
    nd, k = 0.01, 1e-3
    w = rng.normal(scale=nd * np.sqrt(fs), size=(n,))
    r = allan_deviation(w, fs, "octave")
    ok = 4 * np.sqrt(2 / r.edf) <= 0.05  # 5 % is at least 4 standard deviations of the estimate
    assert ok.sum() >= 6
    np.testing.assert_allclose(r.avar[ok], nd**2 / r.tau[ok], rtol=0.05)
    # EDF check: the 95 % chi-square intervals cover the truth at (almost) every tau
    r95 = allan_deviation(w, fs, "octave", ci=0.95)
    inside = (nd / np.sqrt(r.tau) > r95.adev_lo) & (nd / np.sqrt(r.tau) < r95.adev_hi)
    assert inside.mean() >= 0.8
    rw = np.cumsum(rng.normal(scale=k / np.sqrt(fs), size=(n,)))
    r2 = allan_deviation(rw, fs, [1, 2, 5, 10])
    np.testing.assert_allclose(r2.avar, k**2 * r2.tau / 3, rtol=0.05)


def test_multichannel_equals_single_channel(rng):
    y = rng.normal(size=(5000, 3))
    r = allan_deviation(y, 50.0, channels=("x", "y", "z"))
    assert r.adev.shape == (r.tau.size, 3)
    for c in range(3):
        np.testing.assert_allclose(r.channel(c).adev, allan_deviation(y[:, c], 50.0).adev, rtol=1e-12)
    assert r.channel("y").channels == ("y",)
    d = r.to_dict()
    assert len(d["adev"]) == r.tau.size and d["channels"] == ["x", "y", "z"]


def test_memmap_input_matches(tmp_path, rng):
    y = rng.normal(size=(30_000, 2))
    p = tmp_path / "y.npy"
    np.save(p, y)
    mm = np.load(p, mmap_mode="r")
    np.testing.assert_allclose(allan_deviation(mm, 10.0).adev, allan_deviation(y, 10.0).adev, rtol=1e-12)


def test_precision_with_large_offset(rng):
    # a constant offset 1e6 times the noise does not change the statistic
    y = rng.normal(size=50_000)
    a = allan_deviation(y, 1.0).adev
    b = allan_deviation(y + 1e6, 1.0).adev
    np.testing.assert_allclose(a, b, rtol=1e-6)


def test_tau_grids():
    assert np.array_equal(tau_grid(1000, 1.0, "octave"), [1, 2, 4, 8, 16, 32, 64, 128, 256])
    assert np.array_equal(tau_grid(1000, 1.0, "decade"), [1, 2, 4, 10, 20, 40, 100, 200, 400])
    g = tau_grid(100_000, 10.0, ("log", 30))
    assert g[0] == 0.1 and np.all(np.diff(g) > 0) and 20 <= g.size <= 40  # about n, doubling-closed
    assert np.array_equal(tau_grid(100, 2.0, [0.5, 1.0, 1.0]), [0.5, 1.0])


def test_nan_raises_with_location():
    y = np.ones((100, 2))
    y[37, 1] = np.nan
    with pytest.raises(NonFiniteError, match="row 37, column 1"):
        allan_deviation(y, 1.0)


def test_nan_segments_pool_exactly(rng):
    y = rng.normal(size=4001)
    y[2000] = np.nan
    r = allan_deviation(y, 1.0, [1, 2, 4, 8], nan_policy="segments")
    assert r.segments[0].tolist() == [[0, 2000], [2001, 4001]]
    at = pytest.importorskip("allantools")
    s, c = 0.0, 0
    for part in (y[:2000], y[2001:]):
        _, dev, _, n = at.oadev(part, rate=1.0, data_type="freq", taus=[8.0])
        s += dev[0] ** 2 * n[0]
        c += n[0]
    np.testing.assert_allclose(r.adev[-1], np.sqrt(s / c), rtol=1e-10)
    assert r.n_terms[-1] == c


def test_time_gaps(rng):
    y = rng.normal(size=1000)
    t = np.arange(1000) / 10.0
    t[500:] += 3.0
    with pytest.raises(InvalidInputError, match="time gap"):
        allan_deviation(y, 10.0, t=t)
    r = allan_deviation(y, 10.0, t=t, nan_policy="segments")
    assert r.segments[0].tolist() == [[0, 500], [500, 1000]]


def test_bad_inputs():
    with pytest.raises(InvalidInputError, match="kind"):
        allan_deviation(np.ones(10), 1.0, kind="nope")
    with pytest.raises(InvalidInputError, match="fs"):
        allan_deviation(np.ones(10), -1.0)
    with pytest.raises(ShapeError, match="shape"):
        allan_deviation(np.ones((2, 2, 2)), 1.0)
    with pytest.raises(InsufficientDataError, match="at least"):
        allan_deviation(np.ones(1), 1.0)
    with pytest.raises(InsufficientDataError, match="at most"):
        allan_deviation(np.ones(100), 1.0, taus=[80.0])
    with pytest.raises(InvalidInputError, match="taus"):
        allan_deviation(np.ones(100), 1.0, taus="weird")
    with pytest.raises(InvalidInputError, match="input"):
        allan_deviation(np.ones(100), 1.0, input="volts")


def test_channels_in_rows_are_refused():
    from imunav.noise import allan_deviation, psd

    x = np.random.default_rng(0).normal(size=(6, 5000))
    with pytest.raises(ShapeError, match=r"transposed: pass x\.T"):
        allan_deviation(x, 100.0)
    with pytest.raises(ShapeError, match="transposed"):
        psd(x, 100.0)
    assert allan_deviation(x.T, 100.0).adev.shape[1] == 6
