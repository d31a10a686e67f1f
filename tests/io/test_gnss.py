"""imunav.io.gnss: the text-table writer that every KF-GINS file goes through."""

from __future__ import annotations

import io

import numpy as np
import pytest

from imunav.io.gnss import read_table, write_table


def _savetxt(a: np.ndarray, fmt: str) -> bytes:
    """The writer's reference: numpy.savetxt (what write_table called before it formatted in bulk)."""
    s = io.StringIO()
    np.savetxt(s, a, fmt=fmt, delimiter=" ")
    return s.getvalue().encode("latin-1")


def _hard_values(rng: np.random.Generator) -> np.ndarray:
    """Values where a fixed-point formatter goes wrong: signed zeros, negatives that round to zero, exact and
    inexact ties at the 9th and 3rd decimal, the edges of the integer path (2^52 / 10^D), GPS seconds of week,
    NaN and infinities, huge and tiny magnitudes."""
    special = [0.0, -0.0, -1e-12, 5e-10, -5e-10, 1.5e-9, 2.5e-9, 1.0000000005, 0.0005, -0.0015, 0.1, 604799.99999999995,
               456300.01, 2.0**52 / 1e9, np.nextafter(2.0**52 / 1e9, 0), -2.0**52 / 1e9, 2.0**52 / 1e3,
               np.nextafter(2.0**52 / 1e3, 0), 123456789.123456789, -9.87654321e15, 1e300, -1e-300, 5e-324,
               np.nan, np.inf, -np.inf]
    return np.r_[special, 0.5e-9 * np.arange(-400, 400), 0.5e-3 * np.arange(-400, 400),
                 rng.uniform(-1, 1, 3000) * 10.0 ** rng.integers(-12, 8, 3000),
                 np.round(rng.uniform(-1000, 1000, 2000), 9) + 5e-10]


@pytest.mark.parametrize("fmt", ["%-15.9f", "%-8.3f", "%.6e", "%d"])
def test_write_table_writes_the_bytes_of_numpy_savetxt(tmp_path, fmt):
    """The bulk formatter against numpy.savetxt, byte for byte, on values that are hard to format (rows with NaN,
    inf or huge values take the slow path, in order with the others) and on a (N, k) column."""
    rng = np.random.default_rng(3)
    a = _hard_values(rng)
    a = a[: a.size // 4 * 4].reshape(-1, 4)
    if fmt == "%d":  # printf's %d of a float: integral values only (numpy.savetxt's %d refuses NaN and inf)
        a = np.round(rng.normal(0, 1e6, a.shape))
    p = write_table(tmp_path / "t.txt", [a[:, 0], a[:, 1:]], fmt=fmt)
    assert p.read_bytes() == _savetxt(a, fmt)


def test_write_table_in_blocks_and_empty(tmp_path, monkeypatch):
    """Rows split across blocks come out in order and whole; no rows write an empty file."""
    import imunav.io.gnss as gnss

    monkeypatch.setattr(gnss, "_ROWS_PER_BLOCK", 7)
    a = np.arange(50.0)[:, None] * [1.0, -0.5, 1e-9]
    a[20, 1] = np.nan
    assert write_table(tmp_path / "b.txt", [a]).read_bytes() == _savetxt(a, "%-15.9f")
    a[20, 1] = 3.0
    write_table(tmp_path / "b.txt", [a])
    np.testing.assert_array_equal(read_table(tmp_path / "b.txt", (3,), "test"), np.round(a, 9))
    assert write_table(tmp_path / "e.txt", [np.zeros((0, 3))]).read_bytes() == b""


def test_read_table_takes_any_ascii_whitespace_and_names_a_ragged_line(tmp_path):
    """Tabs, CR LF line ends, blank and indented lines read as spaces; a short line is refused by its number."""
    from imunav.errors import FileFormatError

    p = tmp_path / "t.txt"
    p.write_bytes(b"1 2\t3\r\n\n  4\x0b5 6 \r\n\t7 8 9\n")
    np.testing.assert_array_equal(read_table(p, (3,), "test"), [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    p.write_bytes(b"1 2 3\n4 5\n7 8 9\n")
    with pytest.raises(FileFormatError, match="line 2"):
        read_table(p, (3,), "test")
