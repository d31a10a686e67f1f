"""Atomic writes and strict JSON: moved to :mod:`imunav._atomic` (core, below every layer); re-exported here
for the modules and scripts that import them from ``imunav.io._atomic``."""

from imunav._atomic import atomic_path, check_outputs, check_writable, json_text, jsonable, read_json, write_json

__all__ = ["atomic_path", "check_outputs", "check_writable", "json_text", "jsonable", "read_json", "write_json"]
