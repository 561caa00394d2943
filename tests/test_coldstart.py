"""A first run on a cold cache: the second process compiles what this one then loads."""

import pickle
import subprocess
import sys

import numpy as np
import pytest

from wetclutch.launch import controller as control
from wetclutch.launch import loop as launch
from wetclutch.launch import metrics, ratio_hold
from wetclutch.params import Params
from wetclutch.plant import clutch
from wetclutch.sim import coldstart, integrator
from wetclutch.sim.signals import External, Step
from wetclutch.sim.workspace import new_workspace


def _records(rn):
    net, x0, ext = rn.network.compile()
    return net, ext, new_workspace(net, x0)


def test_the_cores_jobs_are_the_same_for_every_network():
    # one compile serves every network: the records' types do not depend on what the network holds
    launch_rig = coldstart._core_jobs(*_records(clutch.build(Params(), External(0), pwm=False, config="clutch")))
    pwm_step = coldstart._core_jobs(*_records(clutch.build(Params(), Step(1.0, 0.2, 1.0), temp_C=85.0)))
    assert [j[2] for j in launch_rig] == [j[2] for j in pwm_step] == [j[2] for j in coldstart._core_jobs(*_small_records())]


def test_the_closed_loops_jobs_have_the_types_of_a_launchs_arguments(monkeypatch):
    seen = []

    def record(*args):
        seen.append(args)
        raise RuntimeError("recorded")

    monkeypatch.setattr(launch, "_closed_loop", record)
    monkeypatch.setattr(coldstart, "_started", True)
    with pytest.raises(RuntimeError, match="recorded"):
        launch.simulate(Params(), "launch", launch.Conditions(t_ref=100.0, post_sync_hold=True),
                        nominal=metrics.Response.empty())
    net, ext, ws, _, probe, temp, _, _, ctrl, cs, hold, hs = seen[0][:12]
    meas = np.zeros(len(control.MEASURED))  # the loop's own buffer
    t = coldstart.job
    expected = [t(control.step, ctrl, cs, meas, 0.0), t(ratio_hold.step, hold, hs, meas, 0.0, False),
                t(ratio_hold.valve, hs, meas, 0.0, False), t(launch._true_values, net, ws.x, probe, temp, meas)]
    assert launch._cold_jobs(net, ext, ws) == expected


def test_the_second_process_writes_its_jobs_to_the_cache_that_a_fresh_process_loads(tmp_path):
    ws = _small_records()[2]
    job = coldstart.job(integrator._log_modes, 0.0, ws.clm_before, ws)
    env = {"NUMBA_CACHE_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    child = subprocess.run([sys.executable, "-m", "wetclutch.sim.coldstart"], input=pickle.dumps([job]),
                           capture_output=True, env=env, timeout=300)
    assert child.returncode == 0, child.stderr.decode()
    assert child.stdout.decode().split() == ["_log_modes"]  # one line per job done: what the first run waits for
    load = ("import pickle, sys; from wetclutch.sim import integrator as i; "
            "i._log_modes.compile(pickle.load(sys.stdin.buffer)); s = i._log_modes.stats; "
            "print(sum(s.cache_hits.values()), sum(s.cache_misses.values()))")
    again = subprocess.run([sys.executable, "-c", load], input=pickle.dumps(job[2]), capture_output=True, env=env,
                           timeout=300)
    assert again.returncode == 0, again.stderr.decode()
    assert again.stdout.decode().split() == ["1", "0"]  # loaded, not compiled


def test_a_warm_cache_or_a_second_call_starts_no_second_process(monkeypatch):
    launch.simulate(Params(), "launch", launch.Conditions(t_ref=100.0), nominal=metrics.Response.empty())
    started = []
    monkeypatch.setattr(coldstart, "_started", False)
    monkeypatch.setattr(coldstart.subprocess, "Popen", lambda *a, **k: started.append(a))
    coldstart.begin(*_small_records())
    coldstart.begin(*_small_records())
    assert started == []
    assert "compile" not in vars(coldstart.rhs_call)


def _small_records():
    from wetclutch.sim.network import GROUND, Network

    net = Network()
    a = net.body("a", J=1.0, w0=1.0)
    net.clutch("c", a, GROUND, capacity=1.0)
    rec, x0, ext = net.compile()
    return rec, ext, new_workspace(rec, x0)


def test_the_first_compile_of_rhs_call_waits_for_the_second_process(monkeypatch, tmp_path):
    # a stand-in second process that takes its time, leaves a mark and then reports rhs_call done
    mark = tmp_path / "done"
    script = (f"import sys, time, pathlib; sys.stdin.buffer.read(); time.sleep(0.5); "
              f"pathlib.Path({str(mark)!r}).write_text('x'); print('rhs_call', flush=True)")
    popen = subprocess.Popen

    def second_process(args, **kw):
        return popen([sys.executable, "-c", script], **kw)

    monkeypatch.setattr(coldstart, "_started", False)
    monkeypatch.setattr(coldstart, "cold", lambda: True)
    monkeypatch.setattr(coldstart.subprocess, "Popen", second_process)
    monkeypatch.setattr(coldstart.rhs_call, "overloads", {})  # as in a process that has compiled nothing
    net, ext, ws = _small_records()
    coldstart.begin(net, ext, ws)
    assert "compile" in vars(coldstart.rhs_call)
    coldstart.rhs_call.compile(coldstart._core_jobs(net, ext, ws)[0][2])  # what numba's typing of a caller does
    assert mark.exists()  # it waited for the second process's line
    assert "compile" not in vars(coldstart.rhs_call)  # and the hook is gone: later compiles are numba's own
