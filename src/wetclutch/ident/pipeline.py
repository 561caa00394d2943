"""Identification: from measurement files back to the clutch's parameters.

Each estimator is a function over the arrays of checked recordings
(:class:`wetclutch.ident.recordings.Recording`, SI units) that returns its value with a
standard error and the files and time windows it came from (an :class:`Estimate`,
or a small record per run). :func:`identify` runs all estimators that the
recordings support:

* torque onset after a command step: dead time and contact pressure (:func:`onset`), and the
  pressure at which the piston's stroke starts (``stroke_start_Pa``: the reset spring's prestress, and
  with the contact pressure the piston's travel to the plates, the fill volume);
* the CVT ratio from the speeds (:func:`measured_ratio`); where the CVT input turns
  too slowly for the speed sensors, the ratio the rig was set to (``meta.json``) or
  the prior's, noted as such;
* friction versus slip from the slip phase of clutch runs (:func:`friction`), also
  binned by pressure and by oil temperature;
* the inertias ``J_p``, ``J_1``, ``J_s`` from the torque and speed balances of clutch
  runs (:func:`inertias`), where the data excite them;
* the open plates' oil drag from the axle torque before each clutch run's first command change, at the run's oil
  temperature, and referred to 20 C through the oil's viscosity (``drag_20C``, :mod:`wetclutch.ident.drag`);
* static pressure versus command on the plateaus of steps and staircases, with the
  hysteresis between up and down staircases (:func:`static_gain`, :func:`hysteresis`), and the supply pressure
  where the highest steps of a staircase give the same pressure (the valve wide open,
  :func:`wetclutch.ident.supply.supply_pressure`);
* low-order pressure models fitted to steps and relaxations (:func:`step_models`)
  and the frequency response from noise, multisine and chirp runs
  (:func:`frequency_response`), as python-control LTI objects;
* driveline resonance and damping from the ring-out after synchronisation (:func:`resonance`);
* validation of the friction law and of the pressure model on each file left out
  of the fit (:func:`wetclutch.ident.validation.validate`).

The rig's sensors low-pass filter their signals (:data:`wetclutch.rig.sensors.DEFAULT_SENSORS`,
assumed for any rig); each channel is advanced by its filter's low-frequency group
delay before channels are combined, so that fast transients do not pair a new
pressure with an old torque.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import numpy as np

from ..errors import WetclutchError, check_instance, check_integer, kind_of, named
from ..params import Params
from ..physics import actuator
from .drag import REL_SE_MAX as DRAG_REL_SE_MAX, drag_20C, open_drag, per_run
from .dynamics import frequency_response, step_models
from .estimate import BAR, Estimate, source, weighted_mean
from .friction import W_RATIO, commanded_ratio, friction, measured_ratio, slip_samples
from .inertia import J_P_HELD, REL_SE_MAX, InertiaFit, excited, inertias
from .onset import Onset, onset
from .recordings import Recording, same_recording
from .result import NEEDS, Identification, drag_resolved, identified_params
from .ringing import resonance
from .play import play_half_width
from .static import GAIN_GROUPS, hysteresis, plateaus, static_gain
from .supply import supply_pressure
from .validation import validate


def identify(recordings: Sequence[Recording], prior: Params | None = None, mu_order: int = 2,
             progress: Callable[[str], None] | None = None) -> Identification:
    """Run every estimator the recordings support (see the module docstring).

    Parameters
    ----------
    recordings
        Checked recordings (:func:`wetclutch.ident.recordings.load`).
    prior
        Parameters not identified here (piston area, efficiency, friction knee ...,
        and those the recordings do not determine) and the base of the identified
        parameter set; defaults if None.
    mu_order
        Order of the ``mu(slip)`` polynomial.
    progress
        Called with a short description before each file's work.

    Raises
    ------
    WetclutchError
        No recordings, one file given twice or two files holding the same recording, or an order out of range.
    """
    if isinstance(recordings, (str, bytes, os.PathLike)) or not isinstance(recordings, (Iterable, type(None))):
        raise WetclutchError(f"recordings must be a list of recordings ([wetclutch.ident.load(f) for f in files]), "
                             f"not {kind_of(recordings)}")
    recordings = list(recordings or ())
    for i, rec in enumerate(recordings):
        if not isinstance(rec, Recording):
            hint = " (read it first: wetclutch.ident.load(path))" if isinstance(rec, (str, os.PathLike)) else ""
            raise WetclutchError(f"recordings[{i}] must be a recording, not {kind_of(rec)}{hint}")
    if prior is not None:
        check_instance(prior, Params, "prior", "a parameter set (wetclutch.load_params(...)) or None")
    if progress is not None and not callable(progress):
        raise WetclutchError(f"progress must be a function of a file's name, or None, not {kind_of(progress)}")
    prior = prior or Params()
    if not recordings:
        raise WetclutchError("no measurement files to identify")
    _check_distinct(recordings)
    mu_name = named("mu_order", "--mu-order")
    if not 0 <= check_integer(mu_order, mu_name) <= 7:
        raise WetclutchError(f"{mu_name} must be 0..7 (got {mu_order})")
    est: dict[str, Estimate] = {}
    onsets, steps, responses, ringings, points = [], [], [], [], []
    for rec in recordings:
        if progress:
            progress(rec.path.name)
        if (o := onset(rec)) is not None:
            onsets.append(o)
        steps += step_models(rec)
        if (fr := frequency_response(rec)) is not None:
            responses.append(fr)
        if (rg := resonance(rec)) is not None:
            ringings.append(rg)
        points += plateaus(rec)

    if onsets:
        est["contact_pressure_Pa"] = _pressure_over_onsets(onsets, "p_contact")
        if starts := [o for o in onsets if np.isfinite(o.p_start)]:
            est["stroke_start_Pa"] = _pressure_over_onsets(starts, "p_start")
    p_contact = est["contact_pressure_Pa"].value if onsets else actuator.contact_pressure(prior)
    by_rec = {id(o.rec): o for o in onsets}
    clutch_runs = [r for r in recordings if r.config == "clutch"]
    notes: dict[str, tuple[Any, str]] = {}  # parameter path -> (value instead of the prior's or None, why)
    ratio_of = _ratios(clutch_runs, prior, est, notes)
    slips = [s for rec in clutch_runs
             if (s := slip_samples(rec, prior, p_contact, by_rec.get(id(rec)), ratio_of[id(rec)])) is not None]
    if slips:
        est["mu_slip_poly"] = friction(slips, mu_order)
    fits = [f for rec in clutch_runs if (f := inertias(rec, prior, ratio_of[id(rec)])) is not None]
    _inertias(fits, clutch_runs, est, notes)
    # open-clutch oil drag: the axle torque before each run's first command change, back through the CVT, per
    # rad/s of slip; referred to 20 C through the oil's viscosity
    drags = [g for rec in clutch_runs if (g := open_drag(rec, ratio_of[id(rec)], prior.driveline.eta, p_contact))]
    if drags:
        est["oil_drag_Nms"] = per_run(drags)
        est["drag_20C"] = drag_20C(drags)
        if not drag_resolved(est):
            g = est["drag_20C"]
            notes["friction.drag_20C"] = (None, f"not resolved by the runs: {g.value:.3g} ± {g.se:.2g} N m s "
                                                f"(standard error above {DRAG_REL_SE_MAX:.0%} of the value)")
    for key, (config, mode, order) in GAIN_GROUPS.items():
        group = [q for q in points if q.rec.config == config and q.rec.input_mode == mode]
        if (g := static_gain(group, order)) is not None:
            est[key] = g
        if config == "valve-only" and mode == "pwm" and (h := hysteresis(group)) is not None:
            est["valve_hysteresis_bar"] = h
            if (play := play_half_width(group, prior)) is not None:
                est["magnet_play_A"] = play
    supply, why = supply_pressure(points, prior)
    if supply is not None:
        est["supply_pressure_Pa"] = supply
        if supply.value <= prior.hydraulics.p_relief:
            notes["hydraulics.p_relief"] = (None, f"the prior's: it cracks above the highest pressure measured "
                                                  f"({max(supply.extra['top_Pa']) / BAR:.2f} bar), which the supply "
                                                  "bounds")
    elif why:
        for path in ("hydraulics.p_supply", "hydraulics.p_relief"):
            notes[path] = (None, f"{why} (needs {NEEDS['supply_pressure_Pa']})")
    if "valve_gain_poly" in est:
        v = est["valve_gain_poly"]
        est["valve_gain"] = Estimate({"slope_bar_per_duty": v.value[0], "offset_bar": v.value[1]},
                                     {"slope_bar_per_duty": v.se[0], "offset_bar": v.se[1]}, "bar", v.sources)
    if ringings:
        f, fse = weighted_mean(np.array([r.freq for r in ringings]), np.array([r.freq_se for r in ringings]))
        z, zse = weighted_mean(np.array([r.zeta for r in ringings]), np.array([r.zeta_se for r in ringings]))
        src = [source(r.rec, r.t0, r.t1) for r in ringings]
        est["resonance_Hz"] = Estimate(f, fse, "Hz (damped)", src)
        est["damping_ratio"] = Estimate(z, zse, "-", src)
    # the temperature of the identified clutch: the friction law and the drag come from the clutch runs alone,
    # pooled over their temperatures; valve-only runs tell nothing of the clutch's oil
    temp_runs = clutch_runs or list(recordings)
    temps = [r.oil_temp_C for r in temp_runs]
    est["oil_temp_C"] = Estimate(float(np.median(temps)), float(np.std(temps)),
                                 "C (median over the clutch runs)" if clutch_runs else "C (median over the runs)",
                                 [source(r, r.t[0], r.t[-1]) for r in temp_runs])
    _no_torque(clutch_runs, est, notes)
    identified = identified_params(prior, est, {k: v for k, (v, _) in notes.items()})
    result = Identification(list(recordings), prior, est, onsets, slips, points, steps, responses, ringings, fits, [],
                            identified, {k: why for k, (_, why) in notes.items()})
    result.validation = validate(result)
    return result


def _check_distinct(recordings: Sequence[Recording]) -> None:
    """Refuse a file given twice and two files holding the same recording (one run as .mat and as .csv).

    A duplicate would count one run twice in every mean and be validated against itself when the other is left out.

    Raises
    ------
    WetclutchError
        One line naming both files.
    """
    for j, b in enumerate(recordings):
        for a in recordings[:j]:
            if a.path.resolve() == b.path.resolve():
                raise WetclutchError(f"measurement file '{b.path}' is given twice (as '{a.path}' before)"
                                     if str(a.path) != str(b.path) else f"measurement file '{b.path}' is given twice")
            if same_recording(a, b):
                raise WetclutchError(f"measurement files '{a.path}' and '{b.path}' hold the same recording "
                                     "(time and every channel alike): give each run once")


def _pressure_over_onsets(onsets: Sequence[Onset], name: str) -> Estimate:
    """The weighted mean of the runs' pressure ``name`` (an :class:`Onset` field with its ``_se``), Pa."""
    m, se = weighted_mean(np.array([getattr(o, name) for o in onsets]),
                          np.array([getattr(o, f"{name}_se") for o in onsets]))
    return Estimate(m, se, "Pa", [source(o.rec, o.t_command, o.t_command + o.dead_time) for o in onsets])


def _ratios(runs: Sequence[Recording], prior: Params, est: dict[str, Estimate],
            notes: dict[str, tuple[Any, str]]) -> dict[int, float]:
    """The CVT ratio of each clutch run: measured where the speeds give it, else the measured ratio of the
    other runs, else the commanded one (``meta.json``) or the prior's, noted in ``notes``."""
    measured = {id(r): measured_ratio(r) for r in runs}
    good = [(v, r) for r in runs if np.isfinite((v := measured[id(r)])[0])]
    if good:
        m, se = weighted_mean(np.array([v[0] for v, _ in good]), np.array([v[1] for v, _ in good]))
        est["ratio"] = Estimate(m, se, "-", [source(r, r.t[0], r.t[-1]) for _, r in good])
        return {id(r): measured[id(r)][0] if np.isfinite(measured[id(r)][0]) else m for r in runs}
    out = {id(r): commanded_ratio(r) or prior.driveline.ratio for r in runs}
    if runs:
        commanded = sorted({c for r in runs if (c := commanded_ratio(r)) is not None})
        value = float(np.median([out[id(r)] for r in runs]))
        origin = (f"the commanded ratio {', '.join(f'{c:g}' for c in commanded)} (meta.json of the runs)" if commanded
                  else f"the prior ratio {prior.driveline.ratio:g}")
        notes["driveline.ratio"] = (value, f"not measured, {origin} is used: the CVT input speed exceeds {W_RATIO:g} "
                                           "rad/s in too few samples for the speed sensors to give the ratio")
    return out


#: the largest axle torque (N m) a clutch run may show and still have its plates apart (oil drag in cold oil, noise)
OPEN_PLATES_NM = 15.0
#: the estimates that need the plates to carry torque, and the parameters they give
_FROM_TORQUE = {"mu_slip_poly": ("friction.mu_slip_poly", "friction.mu_scale", "friction.mu_slope"),
                "contact_pressure_Pa": ("hydraulics.x_contact",), "resonance_Hz": ("driveline.k_a",),
                "damping_ratio": ("driveline.d_a",)}


def _no_torque(runs: Sequence[Recording], est: dict[str, Estimate], notes: dict[str, tuple[Any, str]]) -> None:
    """Where no clutch run shows torque (the input never pressed the plates), say so for the parameters that need
    it, instead of the bare "no suitable runs"."""
    if not runs or any("T_r" not in r.data for r in runs):
        return
    peak = max(float(np.max(np.abs(r.data["T_r"]))) for r in runs)
    # what the open plates' oil drag and the sensor's noise reach on their own; a clutch that engages carries tens
    # of N m or more
    if peak > OPEN_PLATES_NM:
        return
    why = (f"no clutch run shows the plates' torque (|T_r| at most {peak:.2g} N m, what drag and noise give): the "
           "input may never have pressed the plates; a command step to a higher input does")
    for key, paths in _FROM_TORQUE.items():
        if key not in est:
            for path in paths:
                notes.setdefault(path, (None, why))


def _inertias(fits: Sequence[InertiaFit], runs: Sequence[Recording], est: dict[str, Estimate],
              notes: dict[str, tuple[Any, str]]) -> None:
    """Combine the runs' inertias into estimates where the data excite them; else note why the prior stays."""
    def combined(name: str) -> tuple[float, float, list[InertiaFit]]:
        have = [f for f in fits if name in f.values]
        if not have:
            return float("nan"), float("nan"), have
        return (*weighted_mean(np.array([f.values[name][0] for f in have]),
                               np.array([f.values[name][1] for f in have])), have)

    j1_excited = excited(*combined("J_1")[:2])
    for name, key in (("J_1", "J_1"), ("J_p", "J_p" if j1_excited else J_P_HELD), ("J_s", "J_s")):
        path = f"driveline.{name}"
        m, se, have = combined(key)
        if not have:
            why = ("no clutch runs" if not runs else "no omega_s channel" if name == "J_s" and not any(
                "omega_s" in r.data for r in runs) else "no stretch of the clutch runs with every speed measured")
            notes[path] = (None, why)
        elif excited(m, se):
            est[name] = Estimate(m, se, "kg m^2", [source(f.rec, f.t0, f.t1) for f in have])
        else:
            notes[path] = (None, f"not excited by the data: {m:.3g} ± {se:.2g} kg m^2 "
                                 f"(standard error above {REL_SE_MAX:.0%} of the value)")
