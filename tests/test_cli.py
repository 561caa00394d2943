"""The command line: outputs, one-line errors with exit code 2, no half-written directories."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from inprocess import invoke
from wetclutch.cli import main


def run(*args):
    return invoke(args)


@pytest.mark.parametrize("entry", ["python -m wetclutch", "console script"])
def test_a_new_process_refuses_bad_input_in_one_line_with_exit_2(tmp_path, entry):
    # the other command-line tests run the same main() in the test's process (tests/inprocess.py)
    exe = ([sys.executable, "-m", "wetclutch"] if entry == "python -m wetclutch"
           else [str(Path(sys.executable).with_name("wetclutch"))])
    r = subprocess.run([*exe, "launch", "--oil-temp", "900", "--out", str(tmp_path / "never")], capture_output=True,
                       text=True, timeout=120)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "--oil-temp" in lines[0], r.stderr
    assert r.stdout == "" and not (tmp_path / "never").exists()


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
        (["--t-end", "inf"], "--t-end must be in (0, 600] s"),
        (["--t-end", "1e9"], "--t-end must be in (0, 600] s"),
        (["--t-end", "nan"], "--t-end"),
        (["--dt-out", "0"], "--dt-out"),
        (["--dt-out", "100"], "--dt-out"),
        (["--dt-out", "-0.001"], "--dt-out"),
        (["--dt-out", "nan"], "--dt-out"),
        (["--t-end", "600", "--dt-out", "1e-9"], "at most 1000000 samples"),
        (["--frobnicate"], "unrecognized arguments"),
    ],
)
def test_bad_input_one_line_exit_2_no_output(tmp_path, cli_refuses, args, fragment):
    r = cli_refuses(["simulate", "engage", *args], fragment, tmp_path / "never")
    assert "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("args", "named"), [
    (["launch", "--bogus"], "unrecognized arguments: --bogus"),
    (["verify", "--samples", "5", "--frob", "3"], "unrecognized arguments: --frob 3"),
    (["design", "--kiss", "1"], "unrecognized arguments: --kiss 1")])
def test_an_unknown_option_is_named_before_a_missing_required_one(capsys, args, named):
    # each command lacks its required --out as well: the option that does not exist is the one to name
    with pytest.raises(SystemExit) as exc:
        main(args)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and len(err.strip().splitlines()) == 1 and named in err, err


def test_a_missing_required_option_is_named_and_help_shows_it_required(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["launch"])
    assert exc.value.code == 2 and "the following arguments are required: --out" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["launch", "--bogus", "--help"])
    usage = capsys.readouterr().out
    assert exc.value.code == 0 and "--out DIR" in usage and "[--out DIR]" not in usage, usage


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
        (["launch", "--controller", "baseline", "--adaptation", "a.toml"], "--adaptation: the baseline controller"),
        (["launch", "--hold-time", "2"], "--hold-time needs --post-sync-hold"),
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


def test_a_csv_profile_gives_the_request_the_summary_names_and_refuses_t_ref(tmp_path, cli_refuses):
    # the request from 0 to 80 N m over 0.2 s after the request, then held: judged against 80 N m, not the 100 N m
    # that --t-ref defaults to, and an explicit --t-ref beside it would do nothing
    prof = tmp_path / "profile.csv"
    prof.write_text("time,t_ref\n0,0\n0.2,80\n2,80\n")
    cli_refuses(["launch", "--profile", str(prof), "--t-ref", "70"], "--t-ref", tmp_path / "never")
    out = tmp_path / "run"
    assert main(["launch", "--profile", str(prof), "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["t_ref_Nm"] == pytest.approx(80.0)
    assert abs(s["T_ss"] - 80.0) < 0.1 * 80.0


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


def test_simulate_accepts_the_longest_output_interval(tmp_path):
    # the limits themselves are allowed: one interval over the whole run, two samples
    out = tmp_path / "o"
    assert main(["simulate", "coupled-clutches", "--t-end", "0.5", "--dt-out", "0.5", "--out", str(out)]) == 0
    assert len(pd.read_csv(out / "signals.csv")) == 2


def test_params_export_into_a_missing_directory_is_a_one_line_error(tmp_path, capsys):
    target = tmp_path / "nodir" / "x.toml"
    assert main(["params", "export", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"directory '{target.parent}' does not exist" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("args", "out", "fragment"),
    [
        (["design"], "", "--out must not be empty"),
        (["design"], ".", "--out '.' is or contains the current directory"),
        (["simulate", "engage"], "..", "--out '..' is or contains the current directory"),
        (["verify", "--samples", "1"], "./", "is or contains the current directory"),
        (["export-fmu"], "", "--out must not be empty"),
    ],
)
def test_out_that_cannot_be_replaced_is_refused_before_any_work(tmp_path, args, out, fragment):
    cwd = tmp_path / "work"
    cwd.mkdir()
    (cwd / "keep").write_text("mine")
    r = invoke([*args, "--out", out], cwd=cwd)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and fragment in lines[0], r.stderr
    # neither a temporary nor an .old directory, and the directory's content untouched
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["keep", "work"]


@pytest.mark.parametrize("fault", ["busy", "interrupt"])
def test_a_failed_swap_puts_the_previous_output_back_and_leaves_nothing_else(tmp_path, monkeypatch, fault):
    # the new output's move into place fails (e.g. a busy mount point), or Ctrl-C comes just then
    from wetclutch import output
    from wetclutch.errors import WetclutchError

    target = tmp_path / "out"
    target.mkdir()
    (target / "marker").write_text("old")
    real = output.os.rename

    def rename(src, dst):
        if str(src).endswith(".tmp"):
            raise OSError(16, "Device or resource busy") if fault == "busy" else KeyboardInterrupt
        real(src, dst)

    monkeypatch.setattr(output.os, "rename", rename)
    raised = pytest.raises(WetclutchError, match="cannot write output .*busy") if fault == "busy" else \
        pytest.raises(KeyboardInterrupt)
    with raised:
        with output.atomic_dir(target) as d:
            (d / "new.csv").write_text("time\n")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert [p.name for p in target.iterdir()] == ["marker"] and (target / "marker").read_text() == "old"


def test_options_that_would_be_ignored_are_refused(tmp_path, cli_refuses):
    cli_refuses(["export-fmu", "--pwm", "--controller", "launch"], "--pwm", tmp_path / "c.fmu")
    cli_refuses(["export-fmu", "--pwm", "--controller-file", "c.toml"], "--pwm", tmp_path / "c.fmu")
    cli_refuses(["export-fmu", "--dt", "0.002"], "--dt", tmp_path / "p.fmu")
    # a controller file of the baseline: its kind shows only once it is read
    design = tmp_path / "design"
    assert main(["design", "--controller", "baseline", "--out", str(design)]) == 0
    (tmp_path / "a.toml").write_text("")
    cli_refuses(["launch", "--controller-file", str(design / "controller.toml"), "--adaptation",
                 str(tmp_path / "a.toml")], "--adaptation: the baseline controller", tmp_path / "never")
    # nor does a baseline's launch write an adaptation state it does not have
    assert main(["launch", "--controller", "baseline", "--sequence", "2", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "b" / "sequence.csv").exists() and not (tmp_path / "b" / "adaptation.toml").exists()


@pytest.mark.parametrize(("env", "option", "named"),
                         [({}, ["--scheduler", "garbage"], "--scheduler"),
                          ({"DASK_SCHEDULER_ADDRESS": "garbage"}, [], "DASK_SCHEDULER_ADDRESS")])
def test_malformed_scheduler_address_is_one_line_naming_its_source(tmp_path, cli_refuses, monkeypatch, env, option,
                                                                   named):
    # the half-made client is closed at once: no finalizer's traceback follows the error line at exit
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS", raising=False)
    for k, v in env.items():
        monkeypatch.setenv(k, v)
    r = cli_refuses(["verify", "--samples", "1", "--quiet", *option], f"{named}: cannot reach a dask scheduler",
                    tmp_path / "never")
    assert "Traceback" not in r.stderr and "Exception ignored" not in r.stderr


def test_help_texts(capsys):
    def help_of(*cmd):
        with pytest.raises(SystemExit):
            main([*cmd, "--help"])
        return " ".join(capsys.readouterr().out.split())

    fmu = help_of("export-fmu")
    assert "(default: the plant)" in fmu and "launch, default" not in fmu
    rig = help_of("rig")
    assert "--out DIR output directory" in rig and "(default clutch)" in rig
    rep = help_of("report")
    assert "(default 1000; plus corners)" in rep and "(default 200; plus corners)" in rep


def test_counts_of_one_are_singular(tmp_path, capsys):
    rig = tmp_path / "rig"
    assert main(["rig", "step", "--t-end", "3", "--out", str(rig)]) == 0
    assert main(["identify", str(rig / "measured.csv"), "--out", str(tmp_path / "id")]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert line.startswith("identify: 1 file, 1 onset, ") and " 0 frequency responses" in line
    # what it found, each entry a parameter comes from: a clutch step shows the friction law, the contact, the
    # stroke's start and the open plates' drag before it
    assert line.split("; ")[1].split(" -> ")[0] == "mu_slip_poly, contact_pressure_Pa, stroke_start_Pa, drag_20C"


def test_tune_resume_with_other_settings_is_refused_and_cma_says_nothing(tmp_path, cli_refuses):
    state = tmp_path / "state.pkl"
    small = ["--heldout-samples", "2", "--sequence", "1", "--workers", "2", "--quiet", "--state", str(state)]
    # two generations of two: cma enlarges the second for its injected mean and would warn about it
    r = run("tune", "--out", str(tmp_path / "t"), "--samples", "4", "--popsize", "2", "--generations", "2", *small)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    cli_refuses(["tune", "--samples", "6", "--popsize", "3", "--generations", "3", *small],
                "(--samples: 4 in the state, 6 now)", tmp_path / "never")
    cli_refuses(["tune", "--samples", "4", "--popsize", "3", "--generations", "3", *small],
                "(--popsize: 2 in the state, 3 now)", tmp_path / "never")


def test_a_rig_run_whose_plates_never_touch_says_so(tmp_path, capsys):
    # a 1 V step on a clutch whose kiss point is 0.9 bar: identification would find no onset in it
    assert main(["rig", "step", "--t-end", "2", "--set", "hydraulics.p_prestress=90000",
                 "--out", str(tmp_path / "weak")]) == 0
    err = capsys.readouterr().err
    assert err.startswith("warning: the clutch plates never touched (clutch pressure at most 0.9")
    assert "higher --level" in err and err.count("\n") == 1
    assert main(["rig", "step", "--t-end", "2", "--out", str(tmp_path / "default")]) == 0
    assert capsys.readouterr().err == ""
