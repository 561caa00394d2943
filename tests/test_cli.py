"""The command line: outputs, one-line errors with exit code 2, no half-written directories."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from wetclutch.cli import main


def run(*args):
    return subprocess.run([sys.executable, "-m", "wetclutch", *args], capture_output=True, text=True)


def test_simulate_engage_writes_outputs(tmp_path, engage_default):
    out = tmp_path / "eng"
    assert main(["simulate", "engage", "--out", str(out)]) == 0
    df = pd.read_csv(out / "signals.csv")
    assert list(df.columns[:9]) == ["time", "omega_p", "omega_1", "omega_r", "omega_s", "T_c", "T_r", "T_cap", "locked"]
    summary = json.loads((out / "summary.json").read_text())
    for key in ("t_sync", "T_r_peak", "E_clutch", "energy_residual", "mode_switches"):
        assert key in summary
    assert summary["t_sync"] == pytest.approx(engage_default.summary["t_sync"], rel=1e-9)
    np.testing.assert_allclose(df.T_r, engage_default.signals.T_r, rtol=1e-8, atol=1e-8)
    assert (out / "signals.png").stat().st_size > 10_000
    # no temporary directories left beside the output
    assert [p.name for p in tmp_path.iterdir()] == ["eng"]


def test_simulate_with_overrides_and_param_file(tmp_path):
    pf = tmp_path / "p.toml"
    assert main(["params", "export", str(pf), "--set", "driveline.ratio=0.6"]) == 0
    out = tmp_path / "o"
    assert main(["simulate", "engage", "--param-file", str(pf), "--set", "engage.T_cap=60", "--t-end", "5", "--out", str(out)]) == 0
    used = (out / "params.toml").read_text()
    assert "ratio = 0.6" in used and "T_cap = 60" in used
    df = pd.read_csv(out / "signals.csv")
    assert df.time.iloc[-1] == pytest.approx(5.0)


def test_coupled_clutches_columns(tmp_path):
    out = tmp_path / "cc"
    assert main(["simulate", "coupled-clutches", "--out", str(out)]) == 0
    df = pd.read_csv(out / "signals.csv")
    assert list(df.columns[:5]) == ["time", "J1_w", "J2_w", "J3_w", "J4_w"]
    assert len(df) == 1501


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--set", "driveline.bogus=1"], "unknown parameter 'driveline.bogus'"),
        (["--set", "driveline.J_p=-2"], "driveline.J_p"),
        (["--set", "driveline.eta=1.5"], "driveline.eta"),
        (["--set", "driveline.eta"], "expected PATH=VALUE"),
        (["--t-end", "-1"], "--t-end"),
        (["--frobnicate"], "unrecognized arguments"),
    ],
)
def test_bad_input_one_line_exit_2_no_output(tmp_path, cli_refuses, args, fragment):
    r = cli_refuses(["simulate", "engage", *args], fragment, tmp_path / "never")
    assert "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_malformed_param_file(tmp_path):
    pf = tmp_path / "bad.toml"
    pf.write_text("[driveline]\nJ_p = = 3\n")
    out = tmp_path / "never"
    r = run("simulate", "engage", "--param-file", str(pf), "--out", str(out))
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "not valid TOML" in r.stderr and not out.exists()


def test_unknown_scenario():
    r = run("simulate", "warp-drive", "--out", "x")
    assert r.returncode == 2 and "invalid choice" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_failed_run_leaves_previous_output_intact(tmp_path):
    out = tmp_path / "keep"
    out.mkdir()
    (out / "marker").write_text("old")
    r = run("simulate", "engage", "--out", str(out), "--set", "driveline.k_a=-1")
    assert r.returncode == 2
    assert (out / "marker").read_text() == "old"


def test_params_show_lists_units(capsys):
    assert main(["params", "show"]) == 0
    text = capsys.readouterr().out
    assert "driveline.k_a" in text and "N m/rad" in text


def test_launch_writes_signals_summary_plot(tmp_path):
    out = tmp_path / "launch"
    assert main(["launch", "--out", str(out), "--t-ref", "120", "--oil-temp", "60", "--seed", "2"]) == 0
    sig = pd.read_csv(out / "signals.csv")
    assert list(sig.columns) == ["time", "p_clutch", "T_r", "omega_p", "omega_1", "omega_r", "omega_s", "cvt_ratio",
                                 "oil_temp", "t_ref", "u"]
    s = json.loads((out / "summary.json").read_text())
    for key in ("steady_state_error_pct", "t95_s", "t95_settled_s", "overshoot_pct", "ripple_pct", "creep_Nm",
                "jerk_max", "slip_energy_J", "t_sync_s"):
        assert key in s
    assert set(s["requirements"]) == {"steady_state_error", "response_time", "robustness", "standby"}
    assert s["params"]["driveline"]["ratio"] == 0.5
    assert (out / "plot.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["launch", "--t-ref", "-3"], "--t-ref"),
        (["launch", "--oil-temp", "900"], "--oil-temp"),
        (["launch", "--controller", "fuzzy"], "invalid choice"),
        (["launch", "--profile", "nonexistent.csv"], "--profile"),
        (["launch", "--set", "friction.mu_scale=0"], "friction.mu_scale"),
        (["verify", "--samples", "-4"], "--samples"),
        (["verify", "--workers", "0"], "--workers"),
        (["report", "--baseline-samples", "-1"], "--baseline-samples"),
        (["launch", "--seed", "-1"], "--seed"),
        (["verify", "--seed", "-1"], "--seed"),
        (["report", "--seed", "-1"], "--seed"),
        (["launch", "--controller-file", "nonexistent.toml"], "nonexistent.toml"),
        (["verify", "--ranges", "nonexistent.toml"], "nonexistent.toml"),
        (["report", "--baseline-file", "nonexistent.toml"], "nonexistent.toml"),
        (["design", "--set", "hydraulics.A_p=-1"], "hydraulics.A_p"),
        (["design", "--controller", "pi"], "invalid choice"),
        (["verify", "--sequence", "0"], "--sequence"),
        (["report", "--sequence", "101"], "--sequence"),
        (["launch", "--sequence", "0"], "--sequence"),
        (["tune", "--generations", "0"], "--generations"),
        (["tune", "--heldout-seed", "0"], "--heldout-seed"),
        (["rig", "step", "--seed", "-1"], "--seed"),
    ],
)
def test_launch_and_verify_bad_input(tmp_path, cli_refuses, args, fragment):
    cli_refuses(args, fragment, tmp_path / "never")


@pytest.mark.parametrize(
    ("args", "what"),
    [
        (["simulate", "engage", "--param-file"], "parameter file"),
        (["launch", "--controller-file"], "controller file"),
        (["launch", "--adaptation"], "adaptation file"),
        (["verify", "--ranges"], "ranges file"),
        (["identify", "nonexistent.csv", "--channels"], "channel map"),
    ],
)
def test_a_binary_file_where_a_toml_file_belongs_is_refused_in_one_line(tmp_path, cli_refuses, args, what):
    # a recording (here: bytes that are not UTF-8, as in a MAT or MF4 file) given by mistake for a TOML input
    binary = tmp_path / "measured.mat"
    binary.write_bytes(b"MATLAB 5.0 MAT-file\x00\xc8\xff\xfe" * 8)
    cli_refuses([*args, str(binary)], f"{what} '{binary}' is not a text file", tmp_path / "never")


def test_write_error_inside_the_output_is_a_one_line_error(tmp_path):
    # disk full or permissions while the files are written: a WetclutchError (the CLI prints it
    # as one line, exit 2) and neither the temporary nor the target directory stays behind
    from wetclutch.errors import WetclutchError
    from wetclutch.output import atomic_dir

    target = tmp_path / "out"
    with pytest.raises(WetclutchError, match="cannot write output .*No space left"):
        with atomic_dir(target) as d:
            (d / "part.csv").write_text("time\n")
            raise OSError(28, "No space left on device")
    assert list(tmp_path.iterdir()) == []


def test_design_writes_loadable_controller_files_and_their_account(tmp_path, cli_refuses):
    out = tmp_path / "design"
    plant = tmp_path / "plant.toml"
    plant.write_text("[driveline]\nratio = 0.7\n")
    assert main(["design", "--out", str(out), "--param-file", str(plant), "--set", "hydraulics.p_prestress=60000"]) == 0
    md = (out / "design.md").read_text()
    assert "| ratio | 0.7 | - |" in md and "plant (parameter file): driveline.ratio" in md
    assert "--set" in md.split("| p_kiss |")[1].splitlines()[0]  # the prestress came from --set
    assert "SIMC" in md  # the baseline's gains and their rule
    # the launch runs the file's design; a baseline file where a launch controller is needed is refused
    assert main(["launch", "--out", str(tmp_path / "l"), "--controller-file", str(out / "controller.toml"),
                 "--t-ref", "80", "--oil-temp", "85"]) == 0
    cli_refuses(["report", "--controller-file", str(out / "baseline.toml")], "a launch controller is needed",
                tmp_path / "never")
    bad = tmp_path / "bad.toml"
    bad.write_text((out / "controller.toml").read_text().replace('unit = "1/s"', 'unit = "1/min"', 1))
    cli_refuses(["launch", "--controller-file", str(bad)], "settings.ki_t.unit", tmp_path / "never2")
    ranges = tmp_path / "r.toml"
    ranges.write_text("[x]\ntarget = 'driveline.warp'\nlow = 0\nhigh = 1\n")
    cli_refuses(["verify", "--ranges", str(ranges)], "[x].target", tmp_path / "never3")
