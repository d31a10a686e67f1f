"""Readers, writers and dataset loaders.

:func:`read_imu` / :func:`write_imu` handle CSV (column mapping), Parquet,
HDF5, MAT (v5 and v7.3) and NPZ recordings; every writer is atomic.
"""

from imunav.io.core import FORMATS, format_from_suffix, read_imu, write_imu
from imunav.io.datasets import shared_data_dir, shared_data_path

__all__ = ["FORMATS", "format_from_suffix", "read_imu", "write_imu", "shared_data_dir", "shared_data_path"]
