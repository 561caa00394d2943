"""The virtual rig: experiments, files like a real rig, bad options."""

from __future__ import annotations

import json

import numpy as np
import pytest

from inprocess import invoke
from wetclutch.report import rig as rig_report
from wetclutch.rig import experiments as rig
from wetclutch.rig import files as measurement


@pytest.fixture(scope="module")
def step_run(tmp_path_factory):
    res = rig.run("step", level=2.0, seed=3, t_end=4.0)
    out = tmp_path_factory.mktemp("rig") / "step"
    rig_report.write(res, out)
    return res, out


def test_rig_writes_every_file(step_run):
    _, out = step_run
    for f in ("measured.csv", "measured.mf4", "measured.mat", "truth.csv", "meta.json", "plot.png"):
        assert (out / f).stat().st_size > 0, f
    meta = json.loads((out / "meta.json").read_text())
    assert meta["experiment"] == "step" and meta["settings"]["level"] == 2.0
    assert meta["params"]["driveline"]["ratio"] == 0.5


@pytest.mark.parametrize("name", ["measured.csv", "measured.mf4", "measured.mat"])
def test_measurement_files_load_back_with_the_same_values(step_run, name):
    res, out = step_run
    df, units = measurement.read_measurement(out / name)
    cols = ["time", "u", "p_clutch", "T_r", "omega_p", "omega_1", "omega_r", "omega_s", "oil_temp"]
    assert list(df.columns) == cols
    for c in cols:
        np.testing.assert_allclose(df[c], res.measured[c], rtol=1e-8, atol=1e-12)
    if name != "measured.csv":
        assert units["p_clutch"] == "Pa"


def test_measured_is_noisy_truth_at_the_rate(step_run):
    res, _ = step_run
    m, t = res.measured, res.truth
    assert np.allclose(np.diff(m.time), 1e-3)
    p_true = np.interp(m.time, t.time, t.p_clutch)
    resid = m.p_clutch - p_true
    assert 500 < np.std(resid[m.time < 0.9]) < 5000  # sensor noise, Pa


@pytest.mark.parametrize("experiment", ["relaxation", "staircase", "noise", "multisine", "chirp"])
def test_every_experiment_runs(experiment):
    res = rig.run(experiment, config="valve-only", input_mode="pwm", level=0.3, from_=0.05, t_end=4.0, noise=False)
    u, p = res.truth.u, res.truth.p_clutch
    # the command reaches the valve: its pressure swings by more than a bar and rises with the duty cycle
    assert np.ptp(p) > 1e5 and np.corrcoef(u, p)[0, 1] > 0.5


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["step", "--level", "7"], "outside the rig's input range"),
        (["step", "--input-mode", "pwm", "--level", "1.5"], "outside the rig's input range"),
        (["step", "--oil-temp", "300"], "--oil-temp"),
        (["step", "--config", "gearbox"], "invalid choice"),
        (["warp"], "invalid choice"),
        (["step", "--rate", "0"], "--rate"),
        (["step", "--set", "valve.R_coil=-1"], "valve.R_coil"),
    ],
)
def test_bad_rig_options(tmp_path, cli_refuses, args, fragment):
    cli_refuses(["rig", *args], fragment, tmp_path / "never")


def test_calibration_report_cli(tmp_path):
    out = tmp_path / "cal"
    r = invoke(["calibration-report", "--out", str(out)])
    assert r.returncode == 0, r.stderr
    rep = json.loads((out / "report.json").read_text())
    assert rep["total"] == 10 and all("published" in f and "simulated" in f for f in rep["figures"])
    assert rep["passed"] == 10, [f["figure"] for f in rep["figures"] if not f["pass"]]
    text = (out / "report.md").read_text()
    assert "| figure | published | simulated |" in text
    assert (out / "figures.png").exists()
