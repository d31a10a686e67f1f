"""`imunav lab`: what the command refuses before it writes a run folder."""

from __future__ import annotations

from cli_contract import invoke, one_error_line


def test_lab_with_an_empty_step_list_is_refused(tmp_path):
    assert "no lab step" in one_error_line(invoke("lab", "--steps", ",", "--out", tmp_path / "r", "--quiet"))
    assert not (tmp_path / "r").exists()


def test_unknown_option_in_a_step_table_is_exit_2(tmp_path):
    cfg = tmp_path / "lab.toml"
    cfg.write_text("[attitude]\nmc_run = 3\n")  # typo of mc_runs
    line = one_error_line(invoke("lab", "--config", cfg, "--out", tmp_path / "r", "--quiet"))
    assert "mc_run" in line and "[attitude]" in line
    assert not (tmp_path / "r").exists()
