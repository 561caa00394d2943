"""Bad inputs of design/launch/verify/report/tune as a user makes them by mistake or a fuzzer by design: hand-edited
controller, ranges and adaptation files, tune states, output paths, interrupts. Each ends in one line naming the
offending field or option and exit code 2 (an interrupt: 128 + the signal), before any launch is run, and leaves
no half-written output.

No test here designs a controller or launches a clutch: the controller file is made from the design's settings
without its simulated tables, and the work a command would do is replaced by a stand-in that fails the test."""

from __future__ import annotations

import os
import pickle
import stat
import subprocess
import sys
import textwrap
import tomllib

import numpy as np
import pytest
import tomli_w
from hypothesis import given, settings as hsettings
from hypothesis import strategies as st

from inprocess import invoke
from wetclutch import output
from wetclutch.errors import WetclutchError
from wetclutch.launch import adaptation, design, ranges, tune
from wetclutch.launch import settings as files
from wetclutch.params import Params

# --- a controller file without a simulation -------------------------------------------------------------------------


def _design() -> design.Design:
    """A launch design of the built-in rig: its settings as a design takes them, a synthetic feedforward map (rising
    over the valve's input range) in place of the simulated one."""
    plant = Params()
    values = {k: v for k, (v, _) in design.plant_settings(plant).items()} | dict(design.LAUNCH_DEFAULTS)
    values = {k: values[k] for k in design.SETTINGS["launch"]}
    table = np.tile(np.linspace(0.2, 5.0, design.MAP_PRESSURES.size), (design.MAP_TEMPS.size, 1))
    return design.Design("launch", plant, values, {}, design.MAP_TEMPS.copy(), design.MAP_PRESSURES.copy(), table)


DESIGN = _design()
TEXT = files.to_toml(DESIGN)
DATA = tomllib.loads(TEXT)


def _edited(edit) -> str:
    data = tomllib.loads(TEXT)
    edit(data)
    return tomli_w.dumps(data)


_number = st.one_of(st.integers(min_value=-(10**400), max_value=10**400), st.floats(), st.booleans(),
                    st.text(max_size=4))


@hsettings(max_examples=60, deadline=None)
@given(name=st.sampled_from(sorted(design.SETTINGS["launch"])), value=_number)
def test_any_setting_value_loads_or_gives_one_line_naming_it(name, value):
    # an integer too large for a float (TOML has them) was an OverflowError traceback
    text = _edited(lambda d: d["settings"][name].__setitem__("value", value))
    try:
        files.loads(text, "c.toml")
    except WetclutchError as e:
        assert "\n" not in str(e) and f"settings.{name}.value" in str(e) and len(str(e)) < 300


def _set_cell(d, value, row=1, col=5):
    d["tables"]["input_V"][row][col] = value


@pytest.mark.parametrize(("edit", "fragment"), [
    # the valve takes 0.2..5 V: a map beyond it is no inverse of any valve (e.g. written in mA or by a slip)
    (lambda d: _set_cell(d, 100.0), "tables.input_V: must lie within the valve's input range 0.2..5 V"),
    (lambda d: _set_cell(d, -1.0), "tables.input_V: must lie within the valve's input range"),
    # an inverse static map rises with the pressure
    (lambda d: _set_cell(d, 0.3), "tables.input_V: must not fall as the pressure rises (row 1, 40 C"),
    # the pressure axis in Pa, within what a setting in Pa takes (a table in bar would be refused as well)
    (lambda d: d["tables"].__setitem__("pressures_Pa", [p - 1e6 for p in d["tables"]["pressures_Pa"]]),
     "tables.pressures_Pa: must lie within 0..5e+06 Pa"),
    (lambda d: d["tables"].__setitem__("pressures_Pa", [p * 1e6 for p in d["tables"]["pressures_Pa"]]),
     "tables.pressures_Pa: must lie within"),
    (lambda d: d["tables"].__setitem__("temps_C", [200.0, 220.0, 240.0, 260.0, 280.0]),
     "tables.temps_C: must lie within -30..150 C"),
    # a fill pulse of a billion seconds: the valve wide open for the whole launch
    (lambda d: d["tables"].__setitem__("fill_s", [1e9] * 5), "tables.fill_s: must be 5 times in 0..10 s"),
    # keys the loader would ignore: a misspelt edit beside the written value is refused, not dropped
    (lambda d: d["settings"]["ki_t"].__setitem__("valu", 7.0), "settings.ki_t.valu: unknown key"),
    (lambda d: d["tables"].__setitem__("input_v", [[0.2]]), "tables.input_v: unknown key"),
    # each within its range, together no clutch: a kiss point above the supply's pressure (the launch slammed the
    # plates shut before the request, 230 N m of creep)
    (lambda d: d["settings"]["p_kiss"].__setitem__("value", 9e5),
     "settings.p_kiss.value: 900000 Pa is not below settings.p_max (800000 Pa"),
])
def test_hand_edited_tables_and_keys_are_one_line_errors(edit, fragment):
    with pytest.raises(files.ControllerFileError) as e:
        files.loads(_edited(edit), "c.toml")
    assert fragment in str(e.value) and "\n" not in str(e.value)


# --- ranges ------------------------------------------------------------------------------------------------------------


@hsettings(max_examples=60, deadline=None)
@given(key=st.sampled_from(["low", "high"]), value=_number)
def test_any_range_end_parses_or_gives_one_line(key, value):
    entry = {"target": "driveline.ratio", "low": 0.4, "high": 1.0} | {key: value}
    try:
        ranges.parse({"r": entry}, "r.toml")
    except WetclutchError as e:
        assert "\n" not in str(e) and "[r]" in str(e) and len(str(e)) < 300


@pytest.mark.parametrize(("entry", "fragment"), [
    # offsets in Pa written under "rel": once silently limited to factors 0.03..15.6 of the prestress
    ({"target": "hydraulics.p_prestress", "how": "rel", "low": -0.3e5, "high": 0.3e5},
     "[k].low: a factor on the plant's value must be >= 0 (got -30000)"),
    # a range labelled in bar whose values are read in Pa
    ({"target": "hydraulics.p_prestress", "how": "abs", "low": 0.2, "high": 0.5, "unit": "bar"},
     "[k].unit: must be 'Pa'"),
    ({"target": "oil_temp_C", "low": 10.0, "high": 100.0, "unit": "K"}, "[k].unit: must be 'C'"),
    # a factor labelled with the parameter's unit: the values are factors, not pressures
    ({"target": "hydraulics.p_supply", "how": "rel", "low": 0.85, "high": 1.0, "unit": "Pa"},
     "[k].unit: must be '-'"),
])
def test_ranges_whose_values_mean_something_else_than_written_are_refused(entry, fragment):
    with pytest.raises(ranges.RangesError) as e:
        ranges.parse({"k": entry}, "r.toml")
    assert fragment in str(e.value) and "\n" not in str(e.value)


# --- adaptation --------------------------------------------------------------------------------------------------------


@hsettings(max_examples=60, deadline=None)
@given(key=st.sampled_from(["from_C", "to_C", "kiss_Pa", "launches", "friction_factor", "hold_margin_Pa"]),
       value=_number)
def test_any_adaptation_band_value_loads_or_gives_one_line(key, value):
    band = {"from_C": 70.0, "to_C": 90.0, "kiss_Pa": 71000.0, "launches": 2} | {key: value}
    text = tomli_w.dumps({"band_C": 20.0, "band": [band]})
    try:
        adaptation.loads(text, "a.toml")
    except WetclutchError as e:
        assert "\n" not in str(e) and "band[0]" in str(e) and len(str(e)) < 300


# --- tune's state ------------------------------------------------------------------------------------------------------


def _fake_verify(calls):
    def run(design_, plant, n, seed, workers, rs, corners=False, progress=False, sequence=1, **kw):
        calls.append(n)
        rows = [{"index": i, "all_pass": i % 2 == 0,
                 "metrics": {"steady_state_error_pct": 1.0, "t95_settled_s": 0.2, "ripple_pct": 1.0,
                             "creep_Nm": 1.0, "overshoot_pct": 1.0}} for i in range(n)]
        return {"results": rows, "pass_rate": sum(r["all_pass"] for r in rows) / max(n, 1)}
    return run


@pytest.mark.parametrize("content", [pickle.dumps(5), pickle.dumps(("a", "b")), pickle.dumps({"es": 1})],
                         ids=["int", "pair", "dict"])
def test_a_foreign_pickle_as_tune_state_is_one_line(tmp_path, monkeypatch, content):
    calls = []
    monkeypatch.setattr("wetclutch.launch.verify.run", _fake_verify(calls))
    state = tmp_path / "state.pkl"
    state.write_bytes(content)
    with pytest.raises(WetclutchError, match="cannot resume from .*not a tuning state") as e:
        tune.run(DESIGN, None, [], 2, 0, 1, 2, 1, state)
    assert "\n" not in str(e.value) and calls == []


@pytest.mark.parametrize(("where", "fragment"), [("dir", "is not a file"), ("missing/state.pkl", "does not exist")])
def test_a_tune_state_that_cannot_be_saved_is_refused_before_the_search(tmp_path, monkeypatch, where, fragment):
    # a directory, or a file in a directory that is not there: the save after the first generation failed with a
    # traceback (IsADirectoryError, FileNotFoundError), the generation lost
    calls = []
    monkeypatch.setattr("wetclutch.launch.verify.run", _fake_verify(calls))
    (tmp_path / "dir").mkdir()
    with pytest.raises(WetclutchError, match=fragment):
        tune.run(DESIGN, None, [], 2, 0, 1, 2, 1, tmp_path / where)
    assert calls == []


def test_a_tune_state_whose_save_fails_later_is_one_line_and_leaves_no_temporary(tmp_path, monkeypatch):
    calls = []
    fake = _fake_verify(calls)
    box = tmp_path / "box"
    box.mkdir()

    def run(*a, **kw):
        if box.exists():  # the state's directory vanishes under the search (an unmounted disk, a clean-up)
            box.rmdir()
        return fake(*a, **kw)

    monkeypatch.setattr("wetclutch.launch.verify.run", run)
    with pytest.raises(WetclutchError, match="cannot save the search to --state"):
        tune.run(DESIGN, None, [], 2, 0, 1, 2, 1, box / "state.pkl")
    assert list(tmp_path.iterdir()) == []


# --- the command line: refused before any work -------------------------------------------------------------------------


@pytest.fixture
def no_work(monkeypatch):
    """Designs, launches, verifications and tunings fail the test: what is checked must be checked before them."""
    def work(*a, **kw):
        raise AssertionError("work started before the inputs were checked")
    for name in ("wetclutch.launch.design.design", "wetclutch.launch.loop.sequence", "wetclutch.launch.verify.run",
                 "wetclutch.launch.tune.run"):
        monkeypatch.setattr(name, work)


def _refused(args, fragment):
    r = invoke(args)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and fragment in r.stderr, r.stderr


@hsettings(max_examples=60, deadline=None)
@given(text=st.text(min_size=1, max_size=8), where=st.sampled_from(["option", "choice", "command", "setting"]))
def test_any_text_where_an_option_belongs_is_refused_in_one_line(text, where):
    # argparse's own messages quote the user's token as typed: a line break in it must not break the line
    args = {"option": ["launch", f"--x{text}", "--out", "o"], "choice": ["launch", "--controller", f"x{text}"],
            "command": [f"x{text}"], "setting": ["launch", "--set", f"x{text}=1", "--out", "o"]}[where]
    r = invoke(args)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1 and r.stdout == "", r.stderr


def test_an_out_that_is_a_file_is_refused_before_any_work(tmp_path, no_work):
    afile = tmp_path / "afile"
    afile.write_text("mine")
    ctrl = tmp_path / "c.toml"
    ctrl.write_text(TEXT)
    _refused(["verify", "--samples", "1", "--controller-file", str(ctrl), "--out", str(afile)],
             "is a file, not a directory")
    _refused(["launch", "--controller-file", str(ctrl), "--out", str(afile / "sub")],
             f"'{afile}' is a file, not a directory")
    assert afile.read_text() == "mine"


def test_tune_refuses_no_held_out_plants_and_a_state_inside_its_output_before_the_search(tmp_path, no_work):
    ctrl = tmp_path / "c.toml"
    ctrl.write_text(TEXT)
    out = tmp_path / "t"
    base = ["tune", "--controller-file", str(ctrl), "--samples", "2", "--generations", "1", "--popsize", "2",
            "--out", str(out)]
    _refused([*base, "--heldout-samples", "0"], "--heldout-samples must be >= 1")
    out.mkdir()
    # the output directory is replaced as a whole at the end: a state inside it would go with it
    _refused([*base, "--heldout-samples", "1", "--state", str(out / "state.pkl")],
             "lies inside --out")


@pytest.mark.parametrize(("content", "option", "fragment"), [
    ("time;t_ref\n0;50\n1;60\n", "--profile", "needs numeric columns 'time' and 't_ref'"),
    ("band_C = 10.0\n", "--adaptation", "band_C must be 20"),
], ids=["profile", "adaptation"])
def test_launch_reads_its_profile_and_adaptation_before_designing(tmp_path, no_work, content, option,
                                                                  fragment):
    f = tmp_path / "input.file"
    f.write_text(content)
    _refused(["launch", option, str(f), "--out", str(tmp_path / "l")], fragment)


# --- outputs -----------------------------------------------------------------------------------------------------------


def test_an_output_directory_is_made_with_the_usual_permissions(tmp_path):
    # mkdtemp's private 0700 stayed on the output: a colleague (or a web server) could not read a report
    mask = os.umask(0o022)
    try:
        with output.atomic_dir(tmp_path / "o") as d:
            (d / "x.txt").write_text("x")
    finally:
        os.umask(mask)
    assert stat.S_IMODE((tmp_path / "o").stat().st_mode) == 0o755


_INTERRUPTED = textwrap.dedent("""
    import os, signal, sys
    import wetclutch.report.design as report
    from wetclutch.cli import main

    def write(designs, out):
        from wetclutch.output import atomic_dir
        with atomic_dir(out) as d:
            (d / "half.toml").write_text("half")
            {action}

    report.write = write
    import wetclutch.launch.design as design
    design.design = lambda *a, **k: None
    sys.exit(main(["design", "--controller", "launch", "--out", sys.argv[1]]))
""")


@pytest.mark.parametrize(("action", "code", "name"), [
    ("os.kill(os.getpid(), signal.SIGTERM)", 143, "SIGTERM"),
    ("raise KeyboardInterrupt", 130, "SIGINT"),
], ids=["sigterm", "ctrl-c"])
def test_an_interrupted_command_says_so_in_one_line_and_leaves_nothing(tmp_path, action, code, name):
    # SIGTERM (a job's time limit, a service stop) killed the process on the spot: its temporary directory stayed
    # and a verification's workers were orphaned; Ctrl-C printed a traceback
    script = tmp_path / "run.py"
    script.write_text(_INTERRUPTED.format(action=action))
    work = tmp_path / "work"
    work.mkdir()
    r = subprocess.run([sys.executable, str(script), "out"], capture_output=True, text=True, cwd=work, timeout=120)
    assert r.returncode == code, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0] == f"wetclutch: interrupted ({name}); 'out' not written", r.stderr
    assert list(work.iterdir()) == []


def test_a_relative_range_on_a_parameter_that_is_zero_says_it_varies_nothing():
    # a factor on 0 is 0: the report showed the range's bins as if the clutches had differed in it
    rs = ranges.parse({"mu_temp": {"target": "thermal.mu_temp", "how": "rel", "low": 0.5, "high": 2.0},
                       "ratio": {"target": "driveline.ratio", "how": "rel", "low": 0.9, "high": 1.1}})
    fitted, notes = ranges.fit(rs, Params())
    assert [r.name for r in fitted] == ["mu_temp", "ratio"]
    assert len(notes) == 1 and notes[0].startswith("mu_temp (thermal.mu_temp, rel) varies nothing on this plant")


def test_an_adaptation_whose_kiss_point_the_plant_cannot_reach_is_refused(tmp_path, no_work):
    # learnt on another clutch or hand-edited: a kiss point of 49 bar on a supply of 8 bar had the controller hold
    # the valve open for a contact that never came, the plates slammed shut before the request (creep 230 N m)
    a = tmp_path / "a.toml"
    a.write_text(tomli_w.dumps({"band_C": 20.0, "band": [{"from_C": 70.0, "to_C": 90.0, "kiss_Pa": 4.9e6,
                                                          "launches": 2}]}))
    _refused(["launch", "--adaptation", str(a), "--out", str(tmp_path / "l")],
             "band 70..90 C: kiss_Pa 4.9e+06 Pa is not below the highest pressure the plant's supply gives")


_BAD_RANGES = "[fill]\ntarget = 'hydraulics.x_contact'\nhow = 'abs'\nlow = 0.7\nhigh = 1.3\n"  # factors as metres


@pytest.mark.parametrize("command", [["verify", "--samples", "1"], ["report", "--samples", "1"],
                                     ["tune", "--samples", "2", "--heldout-samples", "1"]])
def test_ranges_that_leave_the_physical_range_are_refused_before_the_design(tmp_path, no_work, command):
    # they were found by the verification itself: after the design (minutes on a new plant) and, for the main job,
    # after its twelve nominal launches
    r = tmp_path / "r.toml"
    r.write_text(_BAD_RANGES)
    _refused([*command, "--ranges", str(r), "--out", str(tmp_path / "o")],
             "range [fill] at 0.7 leaves the plant's physical range")


def test_the_main_job_refuses_its_ranges_before_the_nominal_launches(monkeypatch):
    from wetclutch.launch import campaign

    def launch(*a, **kw):
        raise AssertionError("a nominal launch before the ranges were checked")

    monkeypatch.setattr("wetclutch.launch.loop.simulate", launch)
    with pytest.raises(ranges.RangesError, match=r"range \[fill\] at 0.7"):
        campaign.main_job(Params(), DESIGN, DESIGN, ranges.parse(tomllib.loads(_BAD_RANGES)), samples=1,
                          baseline_samples=0, workers=1)


def test_a_negative_held_out_seed_is_named_as_such(tmp_path, no_work):
    # it was "--seed must be >= 0" while --seed was 0
    _refused(["tune", "--heldout-seed", "-1", "--out", str(tmp_path / "t")], "--heldout-seed must be >= 0")


@pytest.mark.parametrize("command", [["design", "--param-file", "{d}/params.toml"],
                                     ["verify", "--controller-file", "{d}/params.toml"],
                                     ["identify", "{d}/params.toml"]], ids=["design", "verify", "identify"])
def test_an_input_inside_the_output_directory_is_refused(tmp_path, no_work, command):
    # the output replaces its directory as a whole: `design --param-file ident/params.toml --out ident` deleted the
    # identification, `identify runs/*/measured.mf4 --out runs` the recordings
    d = tmp_path / "d"
    d.mkdir()
    (d / "params.toml").write_text("[driveline]\nratio = 0.6\n")
    _refused([*(a.format(d=d) for a in command), "--out", str(d)], "lies inside --out")
    assert (d / "params.toml").exists()
