"""Moved to :mod:`imunav.toml` (the one TOML reader and writer, in the core layer); re-exported here."""

from imunav.toml import read_toml, toml_text

__all__ = ["read_toml", "toml_text"]
