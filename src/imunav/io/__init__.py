"""Readers, writers and dataset loaders."""

from imunav.io.datasets import shared_data_dir, shared_data_path

__all__ = ["shared_data_dir", "shared_data_path"]
