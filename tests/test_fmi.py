"""The FMUs: export, FMPy's validation, FMPy simulation against the native run of the same inputs.

Tolerance. The plant FMU advances the same engine as the native closed launch loop, with
the same tolerances, re-deciding the clutch modes after every input change exactly as
the loop does after every controller sample; the same inputs therefore give the same
run. What can differ is the round-off of the communication times (FMPy accumulates
``t += h``, the loop computes ``(k + 1) h``), which moves a step end by ~1e-16 s. So the
FMU must match to 1e-6 of each signal's range (measured: states identical, torques
within 1e-8 of their range), and the lock state exactly.

A closed loop is another matter: the plant FMU's outputs are computed outside the compiled
loop and may differ from the loop's own measurement in the last bit, and the loop (stick/slip,
the valve stem's friction, the dither) carries a last-bit difference into 1e-3 of a signal's
range within 0.1 s of slip (measured: last-bit differences from the first samples, above
1e-9 of the range 70 ms after the request). The closed loop of the two FMUs must therefore match
the native one to 1e-6 through the fill and the hold, up to the request, and give the same launch
figures.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

from inprocess import invoke
from wetclutch import params
from wetclutch.errors import WetclutchError
from wetclutch.launch import Conditions, metrics, simulate
from wetclutch.launch.controller import MEASURED

TOL = 1e-6  # of each signal's range
DT = 1e-3


def _export(out: Path, *args: str) -> Path:
    r = invoke(["export-fmu", "--out", str(out), *args])
    assert r.returncode == 0, r.stderr
    return out


@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("fmu")
    return {"plant": _export(d / "plant.fmu"), "launch": _export(d / "launch.fmu", "--controller", "launch")}


def _close(actual: np.ndarray, expected: np.ndarray, name: str) -> None:
    scale = max(float(np.ptp(expected)), 1e-12)
    err = float(np.max(np.abs(actual - expected)))
    assert err <= TOL * scale, f"{name}: max error {err:.3g} > {TOL:g} x range {scale:.3g}"


@pytest.mark.parametrize("product", ["plant", "launch"])
def test_fmus_pass_fmpy_validation(fmus, product):
    assert validate_fmu(str(fmus[product])) == []
    md = read_model_description(str(fmus[product]))
    assert md.fmiVersion == "2.0" and md.coSimulation is not None
    names = {v.name: v for v in md.modelVariables}
    if product == "plant":
        assert {"u", "road_load", "oil_temp_C"} <= {n for n, v in names.items() if v.causality == "input"}
        assert {"p_clutch", "T_c", "T_r", "omega_p", "omega_1", "omega_s", "locked"} <= {
            n for n, v in names.items() if v.causality == "output"}
        # the parameters are FMU parameters, with the exported values as start values
        assert float(names["driveline.ratio"].start) == params.Params().driveline.ratio
        assert names["friction.mu_slip_poly[2]"].causality == "parameter"
    else:
        assert {*MEASURED, "t_ref"} == {n for n, v in names.items() if v.causality == "input"}
        assert [n for n, v in names.items() if v.causality == "output"] == ["u"]
        assert {n for n, v in names.items() if v.causality == "parameter"} == {"kiss_Pa", "hold_margin_Pa"}
        # a master taking the default step size steps one controller sample at a time
        assert float(md.defaultExperiment.stepSize) == DT


@pytest.mark.parametrize(("oil", "load"), [(None, None), (85.0, 25.0)])
def test_plant_fmu_matches_the_native_run_of_the_same_inputs(fmus, oil, load):
    # the native run: a launch on ideal sensors (its valve input is then a function of the true signals only)
    p = params.Params() if load is None else params.load(None, {"engage.T_load": load})
    res = simulate(p, "launch", Conditions(t_ref=120.0, oil_temp_C=oil, noise=False))
    s, truth = res.signals, res.truth
    n = len(s)
    inputs = np.zeros(n, dtype=[("time", float), ("u", float), ("road_load", float), ("oil_temp_C", float)])
    inputs["time"], inputs["u"] = s["time"], s["u"]
    inputs["road_load"] = p.engage.T_load
    inputs["oil_temp_C"] = p.rig.oil_temp_C if oil is None else oil
    out = simulate_fmu(str(fmus["plant"]), start_time=0.0, stop_time=(n - 1) * DT, step_size=DT, output_interval=DT,
                       input=inputs, output=["p_clutch", "T_r", "T_c", "omega_s", "locked"])
    assert len(out) == n
    for name in ("p_clutch", "T_r", "T_c", "omega_s"):
        _close(out[name], truth[name].to_numpy(), name)
    assert np.array_equal(out["locked"].astype(int), truth["locked"].to_numpy().astype(int))
    assert truth["locked"].iloc[-1] == 1  # the run went through synchronisation


def _slave(path: Path, tmp: Path) -> tuple[FMU2Slave, dict[str, int]]:
    md = read_model_description(str(path))
    unzipped = tmp / path.stem
    with zipfile.ZipFile(path) as z:
        z.extractall(unzipped)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(unzipped), modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=path.stem)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu, {v.name: v.valueReference for v in md.modelVariables}


def test_plant_and_controller_fmus_close_the_loop_like_the_native_launch(fmus, tmp_path):
    res = simulate(params.Params(), "launch", Conditions(t_ref=100.0, noise=False))
    s, truth = res.signals, res.truth
    n = len(s)
    plant, pv = _slave(fmus["plant"], tmp_path)
    ctrl, cv = _slave(fmus["launch"], tmp_path)
    oil, ratio = params.Params().rig.oil_temp_C, params.Params().driveline.ratio
    plant_out = ["p_clutch", "T_r", "omega_p", "omega_1", "omega_r", "omega_s"]
    u_log, tr_log, locked = np.zeros(n), np.zeros(n), np.zeros(n)
    try:
        for k in range(n):
            t = k * DT
            y = dict(zip(plant_out, plant.getReal([pv[c] for c in plant_out])))
            tr_log[k] = y["T_r"]
            locked[k] = float(plant.getBoolean([pv["locked"]])[0])
            t_ref = s["t_ref"].iloc[k]
            y |= {"cvt_ratio": ratio, "oil_temp": oil, "t_ref": t_ref}
            ctrl.setReal([cv[c] for c in (*MEASURED, "t_ref")], [y[c] for c in (*MEASURED, "t_ref")])
            ctrl.doStep(t, DT)  # the controller first: its output is the input held over this step
            u_log[k] = ctrl.getReal([cv["u"]])[0]
            plant.setReal([pv["u"]], [u_log[k]])
            plant.doStep(t, DT)
    finally:
        for f in (plant, ctrl):
            f.terminate()
            f.freeInstance()
    exact = s["time"].to_numpy() <= Conditions().t_request
    _close(u_log[exact], s["u"].to_numpy()[exact], "u")
    _close(tr_log[exact], truth["T_r"].to_numpy()[exact], "T_r")
    t = s["time"].to_numpy()
    assert locked[-1] == 1.0  # the FMUs' launch went through synchronisation, and stayed locked
    t_sync = t[np.flatnonzero(locked == 0.0)[-1] + 1]
    fmu = metrics.response(t, tr_log, s["t_ref"].to_numpy(), Conditions().t_request, t_sync)
    native = res.summary
    assert t_sync == pytest.approx(native["t_sync_s"], abs=0.01)
    assert fmu.t95_settled_s == pytest.approx(native["t95_settled_s"], abs=0.005)
    assert fmu.overshoot_pct == pytest.approx(native["overshoot_pct"], abs=1.0)
    assert fmu.steady_state_error_pct == pytest.approx(native["steady_state_error_pct"], abs=0.5)


def test_export_bad_input_is_one_line_and_writes_nothing(tmp_path, cli_refuses):
    cli_refuses(["export-fmu", "--set", "driveline.eta=2"], "driveline.eta", tmp_path / "a.fmu")
    cli_refuses(["export-fmu", "--controller", "launch", "--dt", "1"], "--dt", tmp_path / "b.fmu")
    r = cli_refuses(["export-fmu"], "--out", tmp_path / "c.zip")
    assert "c.zip" in r.stderr
    assert not [p for p in tmp_path.iterdir()]  # no temporary left behind


def test_the_controller_started_from_a_learnt_kiss_point_acts_as_the_native_loop_does():
    # a clutch whose kiss point lies 0.1 bar above the design's, in cold oil: the second launch starts from the kiss
    # point the first one learnt. Fed the second launch's measurements, the exported controller (started from that
    # kiss point, friction factor, its slope with slip and the output inertia) must give the native loop's input at every sample, the
    # search of a learnt kiss point included
    from wetclutch.fmi.controller import Controller
    from wetclutch.launch import design, loop

    base = params.Params()
    plant = params.load(overrides={"hydraulics.p_prestress": base.hydraulics.p_prestress + 0.1e5})
    d = design.cached(base, "launch")
    runs = loop.sequence(plant, d, Conditions(t_ref=100.0, oil_temp_C=20.0), 2)
    learnt = runs[1].summary["kiss_start_Pa"]
    assert learnt != d.settings["p_kiss"]
    ctrl = Controller(design.record(d, DT), learnt, runs[1].summary["friction_factor_start"],
                      runs[1].summary["friction_slope_start"], runs[1].summary["output_inertia_start_kg_m2"])
    assert np.array_equal(_replayed(ctrl, runs[1].signals), runs[1].signals["u"].to_numpy())


def _replayed(ctrl, sg) -> np.ndarray:
    """The inputs ``ctrl`` gives, sample by sample, fed a launch's recorded measurements and request."""
    return np.array([ctrl.step(dict(zip(MEASURED, row)), r) for row, r in zip(sg[list(MEASURED)].to_numpy(),
                                                                             sg["t_ref"])])


def test_the_controller_holds_a_learnt_margin_below_the_kiss_point_as_the_native_loop_does():
    # a cold clutch whose hold pushed the waiting vehicle beyond the creep limit on its first launch (a stiffly
    # damped stem creeping into the supply port): the second launch holds the plates a learnt margin further apart.
    # The exported controller, started from the learnt kiss point and that margin, must give the native loop's input
    # at every sample; started without the margin it holds higher and does not
    from wetclutch.fmi.controller import Controller
    from wetclutch.launch import adaptation, design, loop

    plant = params.load(overrides={
        "hydraulics.p_prestress": 79687.33104791325, "hydraulics.x_contact": 0.0016452917997275848,
        "friction.mu_scale": 1.161949344641164, "friction.mu_slope": 0.5850790391916972,
        "hydraulics.p_supply": 735563.1743817655, "valve.d_stem": 111.63189414728596,
        "driveline.J_1": 0.0026427959483580708, "hydraulics.line_length": 1.8756802503030086,
        "driveline.ratio": 0.4755098635991616, "engage.T_load": 15.893686726351167})
    d = design.cached(params.Params(), "launch")
    runs = loop.sequence(plant, d, Conditions(t_ref=36.7, oil_temp_C=15.8, seed=1320871885, t_max=2.45), 2)
    s = runs[1].summary
    assert runs[0].summary["creep_Nm"] > metrics.REQ_CREEP_NM and s["hold_margin_Pa"] == adaptation.MARGIN_STEP
    args = (design.record(d, DT), s["kiss_start_Pa"], s["friction_factor_start"], s["friction_slope_start"],
            s["output_inertia_start_kg_m2"])
    u = runs[1].signals["u"].to_numpy()
    assert np.array_equal(_replayed(Controller(*args, hold_margin=s["hold_margin_Pa"]), runs[1].signals), u)
    assert not np.array_equal(_replayed(Controller(*args), runs[1].signals), u)
    with pytest.raises(WetclutchError, match="hold_margin must be in 0..10000 Pa"):
        Controller(*args, hold_margin=-1.0)
