"""Tuning: the tail score on results with known answers, a small search, stop and resume."""

import re
from dataclasses import replace

import numpy as np
import pytest

from wetclutch.errors import WetclutchError
from wetclutch.launch import design as designs
from wetclutch.launch import margins, metrics, ranges, tune, verify
from wetclutch.params import Params


def _result(ess, t95, ok):
    return {"metrics": {"steady_state_error_pct": ess, "t95_settled_s": t95, "ripple_pct": 1.0, "creep_Nm": 2.0,
                        "overshoot_pct": 5.0}, "all_pass": ok}


def test_badness_is_the_largest_violation_and_the_score_its_tail():
    r = _result(5.0, 0.3, False)
    assert tune.badness(r) == pytest.approx(0.3 / metrics.REQ_T95_S)
    assert tune.badness({"metrics": {}}) == 10.0
    rows = [_result(1.0, 0.1, True)] * 18 + [_result(30.0, 0.1, False), _result(1.0, 0.8, False)]
    res = {"results": rows, "pass_rate": 0.9}
    # the worst 10 % of 20 samples: the two failures, 3.0 and 4.0 times their limits
    tail = np.mean([30.0 / metrics.REQ_ESS_PCT, 0.8 / metrics.REQ_T95_S])
    assert tune.score(res) == pytest.approx(0.1 + tune.TAIL_WEIGHT * tail)


SMALL = ranges.parse({"request": {"target": "t_ref", "low": 60.0, "high": 140.0},
                      "ratio": {"target": "driveline.ratio", "low": 0.45, "high": 0.6}})


def test_a_small_search_can_be_stopped_and_resumed(tmp_path):
    start = designs.cached(Params(), "baseline")
    state = tmp_path / "state.pkl"
    one = tune.run(start, Params(), SMALL, samples=2, seed=3, generations=1, popsize=2, workers=1, state=state)
    assert state.is_file() and len(one.history) == 1
    both = tune.run(start, Params(), SMALL, samples=2, seed=3, generations=2, popsize=2, workers=1, state=state)
    assert len(both.history) == 2 and both.history[0] == one.history[0]
    # the reported best is the tuned design's own score: verified again on the training plants it scores the same
    again = verify.run(both.design, Params(), 2, 3, 1, SMALL, corners=False, progress=False)
    assert tune.score(again) == pytest.approx(both.best_score, rel=1e-12)
    # the tuned design is the finalist that scores best on the validation plants (seed + 1, twice as many); the
    # start is among the finalists, so the tuned design does no worse there than the start
    val = {name: tune.score(verify.run(d, Params(), 2 * 2, 4, 1, SMALL, corners=False, progress=False))
           for name, d in (("start", start), ("tuned", both.design))}
    assert val["tuned"] == pytest.approx(both.finalists[both.chosen][2], rel=1e-12)
    assert val["start"] == pytest.approx(both.finalists["start"][2], rel=1e-12)
    assert val["tuned"] <= val["start"]
    for name in tune.TUNABLE["baseline"]:
        assert start.settings[name] / tune.SPAN <= both.design.settings[name] <= start.settings[name] * tune.SPAN
        assert both.design.sources[name].startswith("tuned") == (both.chosen != "start")
    if both.chosen == "start":  # a start that does best on the validation plants stays as it was
        assert both.design.settings == start.settings
    other = designs.with_settings(start, kp=start.settings["kp"] * 2)
    with pytest.raises(WetclutchError, match="another tuning"):
        tune.run(other, Params(), SMALL, samples=2, seed=3, generations=3, popsize=2, workers=1, state=state)


@pytest.mark.parametrize(("tau", "theta"), [(0.01, 0.01), (0.05, 0.01), (0.02, 0.005)])
def test_simc_tight_tuning_has_the_published_margins(tau, theta):
    # SIMC with tau_c = theta and tau <= 8 theta cancels the lag: L(s) = e^(-theta s) / (2 theta s), whose phase
    # crosses -180 deg at theta w = pi/2, where |L| = 1/pi (gain margin pi), and whose gain crosses 1 at
    # w = 1/(2 theta), where the phase is -90 deg - 0.5 rad (phase margin 90 - 28.65 deg)
    k = 80.0
    kp = tau / (k * 2 * theta)
    ki = kp / min(tau, 8 * theta)
    gm, pm = margins.pi_margins(k, tau, theta, kp, ki)
    assert gm == pytest.approx(np.pi, rel=2e-3) and pm == pytest.approx(90.0 - np.degrees(0.5), abs=0.05)


def test_the_baseline_keeps_its_margins_over_the_corners():
    d = designs.cached(Params(), "baseline")
    rows = margins.over_corners(d, Params(), ranges.load())
    assert len(rows) == 2 ** sum(r.corner for r in ranges.load())
    # the rule never goes below SIMC's tight tuning, whose margins are the smallest
    assert min(r["gain_margin"] for r in rows) > 2.5 and min(r["phase_margin_deg"] for r in rows) > 55.0


def test_the_corners_of_a_low_prestress_clutch_stay_within_its_physical_range():
    # the kiss point's corners move the prestress by -0.3 and +0.3 bar; on a clutch whose prestress is 0.1 bar the
    # lower one stops at zero (as in the verification) instead of stopping the report
    plant = Params().model_copy(update={"hydraulics": Params().hydraulics.model_copy(update={"p_prestress": 0.1e5})})
    rs = ranges.parse({"kiss": {"target": "hydraulics.p_prestress", "how": "offset", "low": -0.3e5, "high": 0.3e5,
                                "corner": True}})
    rows = margins.over_corners(designs.cached(plant, "baseline"), plant, rs)
    assert [r["corner"]["kiss"] for r in rows] == [pytest.approx(-0.1e5, abs=1.0), 0.3e5]
    assert all(r["gain_margin"] > 1.0 for r in rows)


def test_the_launch_loops_margins_are_conservative_where_the_simulated_launch_rings():
    # a heavy clutch output (J_1 x 10) at the shortest ratio: its resonance on the axle (about 14 Hz) falls to where a
    # fast friction-factor estimate closes a loop through it, unless the estimate takes the output's share of the
    # clutch torque out. Where the linear analysis leaves margin the nonlinear launch is smooth; where it leaves none
    # the launch rings (at the margin itself by 5-20 % as the noise has it), but the estimate's limits keep the ring
    # bounded
    from wetclutch.launch import loop

    plant = Params().model_copy(deep=True)
    plant.driveline.J_1 *= 10.0
    plant.driveline.ratio = 0.4
    fast = designs.with_settings(designs.cached(Params(), "launch"), tau_theta=0.005)
    # a design that believes the output at 0.006 kg m^2: the launch's estimate of 0.01 is not heavy enough against it
    # to be taken within the launch, so the estimate keeps 60 % of the output's share out, the rest rings through
    partial = designs.with_settings(fast, j_1=0.006)
    slow = designs.cached(Params(), "launch")
    cond = loop.Conditions(t_ref=150.0, oil_temp_C=60.0)
    m = {name: margins.launch_margins(d, plant, 60.0, 150.0) for name, d in
         (("fast", fast), ("partial", partial), ("slow", slow))}
    # the undamped frequency sqrt(k_a i^2 / J_1), independent of the analysis code
    assert m["fast"].resonance_hz == pytest.approx(np.sqrt(480.0 * 0.4**2 / 0.01) / (2 * np.pi), rel=1e-9)
    assert margins.estimate_inertia(fast.settings["j_1"], 0.01) == 0.01
    assert margins.estimate_inertia(partial.settings["j_1"], 0.01) == 0.006
    # the linear loop leaves out the estimate's limits and the pressure loop's damping, so it is conservative: the
    # partly told estimate is far beyond its gain margin, the fully told one at it, the default's well within
    assert m["partial"].gain < 0.7 and m["fast"].gain > 0.9 and m["slow"].gain > 1.5
    for seed in (0, 1, 2):
        ripple = {name: loop.simulate(plant, d, replace(cond, seed=seed)).summary["ripple_pct"] for name, d in
                  (("fast", fast), ("partial", partial), ("slow", slow))}
        assert ripple["slow"] < 0.6 * metrics.REQ_RIPPLE_PCT, ripple
        assert ripple["fast"] > ripple["slow"] and ripple["partial"] > ripple["slow"], ripple
        assert max(ripple.values()) < 5.0 * metrics.REQ_RIPPLE_PCT, ripple


def test_the_friction_curve_falling_with_slip_is_judder_the_loop_cannot_damp():
    # dmu/dslip < 0 at the launch's initial slip is a negative damping F_n mu' / i^2 on the clutch output; at a high
    # request through a short ratio with a steep curve it outweighs the axle damping
    plant = Params().model_copy(deep=True)
    plant.driveline.ratio, plant.friction.mu_slope = 0.4, 1.5
    g = margins.driveline(plant, 200.0)
    assert float(np.real(g.poles()).max()) > 0.0
    assert float(np.real(margins.driveline(Params(), 100.0).poles()).max()) < 0.0


def test_mcnemars_exact_test_is_the_binomial_tail_of_the_discordant_plants():
    from math import comb

    start = [True] * 10 + [False] * 8 + [True, False]
    # the candidate passes 7 of the plants the start fails and fails 1 it passes: P(X >= 7), X ~ binomial(8, 1/2)
    cand = [True] * 10 + [True] * 7 + [False] + [False, False]
    b, c, p = tune.against_start(cand, start)
    assert (b, c) == (7, 1)
    assert p == pytest.approx(sum(comb(8, k) for k in (7, 8)) / 2**8, rel=1e-12)
    assert tune.against_start(start, start) == (0, 0, 1.0)
    assert tune.against_start(cand[:-1] + [True], cand) == (1, 0, pytest.approx(0.5))  # one plant apart
    with pytest.raises(ValueError, match="same plants"):
        tune.against_start(cand[:-1], start)


def _verified_by_kp(start, passes):
    """A stand-in for the verification of the finalists: the pass/fail of each plant by the design's ``kp``
    relative to the start's (1, 2 or 0.5), the same for the training and the validation plants."""
    def verified(design, n, seed):
        ok = passes[round(design.settings["kp"] / start.settings["kp"], 6)][:n]
        return {"results": [{"index": i, "all_pass": x, "metrics": {}} for i, x in enumerate(ok)],
                "pass_rate": sum(ok) / n}
    return verified


@pytest.mark.parametrize("case", ["significant", "a lucky few"])
def test_a_candidate_replaces_the_start_only_if_it_passes_significantly_more_plants(case):
    start = designs.cached(Params(), "baseline")
    names = tune.TUNABLE["baseline"]
    base = [True] * 30 + [False] * 10
    if case == "significant":  # kp x2 passes 8 plants more, fails none the start passes
        better = [True] * 38 + [False] * 2
    else:  # kp x2 passes 3 plants more and fails 1 the start passes: a higher pass rate, no evidence
        better = [False] + [True] * 29 + [True] * 3 + [False] * 7
    worse = [True] * 25 + [False] * 15
    t = tune.Tuning(start, start, names, best_x=np.array([np.log(2.0), 0.0]))
    t.start_training = (1.0, 0.75)
    t.best_score, t.best_rate = 0.5, 0.9
    tune._choose(t, np.array([-np.log(2.0), 0.0]), _verified_by_kp(start, {1.0: base, 2.0: better, 0.5: worse}), 20, 0)
    assert set(t.finalists) == {"start", "best on training", "search mean"}
    assert t.finalists["best on training"][2] < t.finalists["start"][2]  # it scores lower either way
    if case == "significant":
        assert t.tests["best on training"][:2] == (8, 0) and t.chosen == "best on training"
        assert t.design.settings["kp"] == pytest.approx(2.0 * start.settings["kp"])
    else:
        assert t.tests["best on training"][:2] == (3, 1) and t.chosen == "start"
        assert t.design is start
    assert t.tests["search mean"][2] == 1.0  # passes no plant the start fails


def test_tune_command_writes_the_finalists_and_keeps_the_design_unless_beaten(tmp_path):
    import json

    from wetclutch.cli import main
    from wetclutch.launch import settings

    out = tmp_path / "t"
    assert main(["tune", "--controller", "baseline", "--samples", "2", "--generations", "1", "--popsize", "2",
                 "--heldout-samples", "2", "--sequence", "1", "--quiet", "--out", str(out)]) == 0
    info = json.loads((out / "tune.json").read_text())
    fin = info["finalists"]
    # a candidate is chosen only if it scores below the start and passes significantly more validation plants
    if info["chosen"] != "start":
        assert fin[info["chosen"]]["validation_score"] < fin["start"]["validation_score"]
        assert fin[info["chosen"]]["p_value"] < tune.SIGNIFICANCE
    written = settings.load(out / "controller.toml")
    start = designs.cached(Params(), "baseline")
    names = tune.TUNABLE["baseline"]
    assert {n: written.settings[n] for n in names} == pytest.approx({n: info["gains"][n]["tuned"] for n in names})
    # the start's gains are the design's: kept unchanged when the start is chosen
    assert {n: info["gains"][n]["start"] for n in names} == pytest.approx({n: start.settings[n] for n in names})
    assert (info["chosen"] == "start") == ({n: written.settings[n] for n in names}
                                           == pytest.approx({n: start.settings[n] for n in names}))
    assert info["pass_rates"]["training"]["tuned"] == fin[info["chosen"]]["training_pass_rate"]
    assert "(chosen)" in (out / "tune.md").read_text()


def test_a_resume_with_other_scoring_settings_is_refused(tmp_path):
    start = designs.cached(Params(), "baseline")
    state = tmp_path / "state.pkl"
    tune.run(start, Params(), SMALL, samples=2, seed=3, generations=2, popsize=2, workers=1, state=state)
    for change, fragment in (({"samples": 3}, "--samples: 2 in the state, 3 now"),
                             ({"popsize": 3}, "--popsize: 2 in the state, 3 now"),
                             ({"seed": 4}, "--seed: 3 in the state, 4 now"),
                             ({"sequence": 2}, "--sequence: 1 in the state, 2 now"),
                             ({"ranges": SMALL[:1]}, "--ranges: ranges "),
                             ({"plant": Params(driveline={"ratio": 0.55})}, "--param-file/--set: plant "),
                             ({"generations": 1}, "--generations 1 is fewer than the 2 generations")):
        kw = {"samples": 2, "seed": 3, "generations": 2, "popsize": 2, "ranges": SMALL, "plant": Params()} | change
        with pytest.raises(WetclutchError, match=re.escape(fragment)):
            tune.run(start, workers=1, state=state, **kw)
    # the same settings resume, with more generations
    more = tune.run(start, Params(), SMALL, samples=2, seed=3, generations=3, popsize=2, workers=1, state=state)
    assert len(more.history) == 3
