"""The result of an identification and the parameter set it implies."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import WetclutchError
from ..params import OIL_TEMP_RANGE_C, Params, describe, load
from ..plant.driveline import axle_for
from .drag import REL_SE_MAX
from .dynamics import FrequencyResponse, StepModel
from .estimate import Estimate, source
from .friction import SlipSamples
from .inertia import InertiaFit
from .onset import Onset
from .recordings import Recording
from .ringing import Ringing
from .static import Plateau

#: entries of ``identified.json`` that are always written (null when the files do not support them)
REPORTED = ("mu_slip_poly", "contact_pressure_Pa", "valve_gain", "clutch_gain_poly_bar_per_V", "resonance_Hz",
            "damping_ratio")

#: parameters that identification determines when the runs allow: dotted path -> identified.json entry it comes from
PARAMS_FROM = {
    "friction.mu_slip_poly": "mu_slip_poly",
    "friction.mu_scale": "mu_slip_poly",
    "friction.mu_slope": "mu_slip_poly",
    "driveline.ratio": "ratio",
    "driveline.J_p": "J_p",
    "driveline.J_1": "J_1",
    "driveline.J_s": "J_s",
    "driveline.k_a": "resonance_Hz",
    "driveline.d_a": "damping_ratio",
    "hydraulics.p_prestress": "stroke_start_Pa",
    "hydraulics.x_contact": "contact_pressure_Pa",
    "valve.I_hyst": "magnet_play_A",
    "rig.oil_temp_C": "oil_temp_C",
    "friction.drag_20C": "drag_20C",
    "hydraulics.p_supply": "supply_pressure_Pa",
    "hydraulics.p_relief": "supply_pressure_Pa",
}
#: the runs each entry of :data:`PARAMS_FROM` needs, for the reason a parameter stays at the prior
NEEDS = {
    "mu_slip_poly": "a slip phase of a clutch run with enough calm samples",
    "ratio": "a clutch run",
    "resonance_Hz": "a ring-out of at least 0.8 s after synchronisation",
    "damping_ratio": "a ring-out of at least 0.8 s after synchronisation",
    "contact_pressure_Pa": "a torque onset after a rising command step of a clutch run",
    "stroke_start_Pa": "a rising command step of a clutch run from an empty clutch, its stroke long enough to show",
    "magnet_play_A": "a staircase of the valve alone in PWM, up and down over the same levels",
    "drag_20C": "a clutch run whose primary slips against the resting output with the plates apart for at least "
                "0.2 s before its first command change (a step from an empty clutch)",
    "supply_pressure_Pa": "a staircase up to the top of the input range whose highest two steps give the same "
                          "pressure (the valve wide open): the valve alone in PWM up to duty 1, or the clutch in warm "
                          "oil (85 C) up to 5 V; a single step to the top does not show it",
}


@dataclass
class Identification:
    """All estimates from a set of recordings."""

    recordings: list[Recording]
    prior: Params
    estimates: dict[str, Estimate]
    onsets: list[Onset]
    slips: list[SlipSamples]
    plateaus: list[Plateau]
    steps: list[StepModel]
    responses: list[FrequencyResponse]
    ringings: list[Ringing]
    inertias: list[InertiaFit]
    validation: list[dict[str, Any]]
    identified: Params
    #: dotted parameter path -> why it comes from the prior (or the commanded value) instead of the runs
    notes: dict[str, str] = field(default_factory=dict)

    def __repr__(self) -> str:
        # a notebook shows this: what was found from what, not every estimate's samples
        found = [k for k, (how, _) in self.sources().items() if how == "identified"]
        return (f"Identification({len(self.recordings)} recordings, {len(self.estimates)} estimates; identified: "
                f"{', '.join(found) or 'nothing'}; from the prior: {len(self.sources()) - len(found)} parameters)")

    def origin(self) -> dict[str, str]:
        """Parameter path -> ``identified`` or ``prior``: how each parameter of :data:`PARAMS_FROM` was obtained,
        as a design's ``origin`` takes it (``wetclutch.launch.design.design(res.identified, "launch",
        res.origin())`` names each setting's source as ``wetclutch design --param-file`` does)."""
        return {k: how for k, (how, _) in self.sources().items()}

    def sources(self) -> dict[str, tuple[str, str]]:
        """Parameter path -> (``identified`` or ``prior``, reason), for the parameters of :data:`PARAMS_FROM`."""
        found = identified_values(self.prior, self.estimates)
        out = {}
        for path, entry in PARAMS_FROM.items():
            if path in found:
                out[path] = ("identified", f"from {entry}")
            else:
                out[path] = ("prior", self.notes.get(path) or f"no suitable runs (needs {NEEDS[entry]})")
        return out

    def as_json(self) -> dict[str, Any]:
        """The content of ``identified.json``: flat, named entries, each with value, se and sources."""
        e = self.estimates
        out: dict[str, Any] = {"files": [{"file": str(r.path), "experiment": r.experiment, "config": r.config,
                                          "input_mode": r.input_mode, "oil_temp_C": r.oil_temp_C,
                                          "duration_s": float(r.t[-1] - r.t[0])} for r in self.recordings]}
        for name, est in e.items():
            out[name] = est.as_json()
        out["dead_time_s"] = [{"oil_temp_C": o.rec.oil_temp_C, "input": o.level, "value": o.dead_time,
                               "se": o.dead_time_se, "source": source(o.rec, o.t_command, o.t_command + o.dead_time)}
                              for o in self.onsets]
        out["pressure_step_models"] = [m.as_json() for m in self.steps]
        out["frequency_responses"] = [r.as_json() for r in self.responses]
        out["validation"] = [{k: v for k, v in e.items() if k != "trace"} for e in self.validation]
        # where each parameter of params.toml comes from, for the design step's account of its settings
        found = identified_values(self.prior, e)
        out["parameters"] = {path: "identified" if path in found else "prior"
                             for path, *_ in describe(self.identified)}
        sources = self.sources()
        out["parameter_reasons"] = {path: why for path, (_, why) in sources.items()}
        why_not = {PARAMS_FROM[path]: why for path, (status, why) in sources.items() if status == "prior"}
        # always present: "not identified" is no typo
        for key in (*REPORTED, "ratio", "J_p", "J_1", "J_s", "drag_20C", "supply_pressure_Pa"):
            why = why_not.get(key, "no suitable runs")
            out.setdefault(key, {"value": None, "se": None, "note": f"not identified: {why}", "sources": []})
        return out


def identified_params(prior: Params, est: dict[str, Estimate], fallback: dict[str, Any] | None = None) -> Params:
    """The prior parameters with the identified values put in (:func:`identified_values`).

    ``fallback`` gives values (not None) that replace the prior's where the runs do not
    identify them, e.g. the commanded CVT ratio.
    """
    fallback = {k: v for k, v in (fallback or {}).items() if v is not None}
    try:
        return load(None, fallback | identified_values(prior, est, fallback), base=prior)
    except WetclutchError as err:
        raise WetclutchError(f"identified values make no valid parameter set: {err}") from None


def drag_resolved(est: dict[str, Estimate]) -> bool:
    """Whether the runs resolve ``friction.drag_20C``: positive, its standard error at most
    :data:`wetclutch.ident.drag.REL_SE_MAX` of its value."""
    if "drag_20C" not in est:
        return False
    value, se = est["drag_20C"].value, est["drag_20C"].se
    return bool(value > 0.0 and se <= REL_SE_MAX * value)


def identified_values(prior: Params, est: dict[str, Estimate],
                      fallback: dict[str, Any] | None = None) -> dict[str, Any]:
    """Dotted parameter path -> identified value, for the parameters the estimates determine.

    ``friction.mu_slip_poly`` (``mu_scale`` 1), ``driveline.ratio``, the inertias
    ``driveline.J_p``, ``J_1``, ``J_s``, ``rig.oil_temp_C``, ``hydraulics.p_prestress`` (the pressure at which
    the stroke starts), ``hydraulics.x_contact`` (from the contact pressure above that prestress, or the
    prior's, with the prior's spring and piston area: the stroke that the pressure's span implies),
    ``valve.I_hyst`` (the magnet's play, from the valve's up and down staircases), ``friction.drag_20C`` (the open
    plates' oil drag referred to 20 C, where the runs resolve it), ``hydraulics.p_supply`` (from a saturated top of
    the static pressure; ``p_relief`` raised to it where the prior's cracks lower), ``driveline.k_a`` and ``d_a``
    (from resonance and damping with the ratio and the
    inertias, identified or else from ``fallback`` or the prior, through the relation
    in :mod:`wetclutch.params`).
    """
    fallback = fallback or {}
    sets: dict[str, Any] = {}
    if "mu_slip_poly" in est:
        sets["friction.mu_slip_poly"] = list(est["mu_slip_poly"].value)
        sets["friction.mu_scale"] = 1.0
        sets["friction.mu_slope"] = 1.0
    ratio = est["ratio"].value if "ratio" in est else fallback.get("driveline.ratio") or prior.driveline.ratio
    if "ratio" in est:
        sets["driveline.ratio"] = ratio
    inertias = {name: float(est[name].value) for name in ("J_p", "J_1", "J_s") if name in est}
    sets |= {f"driveline.{name}": v for name, v in inertias.items()}
    if "oil_temp_C" in est:
        sets["rig.oil_temp_C"] = float(np.clip(est["oil_temp_C"].value, *OIL_TEMP_RANGE_C))
    h = prior.hydraulics
    if "contact_pressure_Pa" in est:
        # both come from the torque onsets: a stroke start only with a contact pressure
        p_contact, p_start = est["contact_pressure_Pa"].value, h.p_prestress
        if "stroke_start_Pa" in est and est["stroke_start_Pa"].value < p_contact:
            p_start = float(est["stroke_start_Pa"].value)
            sets["hydraulics.p_prestress"] = p_start
        if p_contact > p_start:
            sets["hydraulics.x_contact"] = (p_contact - p_start) * h.A_p / h.k_reset
    if "magnet_play_A" in est:
        sets["valve.I_hyst"] = float(est["magnet_play_A"].value)
    if drag_resolved(est):
        sets["friction.drag_20C"] = float(est["drag_20C"].value)
    if "supply_pressure_Pa" in est:
        # the valve's top: the supply pressure, and the relief valve cracks no lower than what was measured
        p_supply = float(est["supply_pressure_Pa"].value)
        sets["hydraulics.p_supply"] = p_supply
        if p_supply > h.p_relief:
            sets["hydraulics.p_relief"] = p_supply
    if "resonance_Hz" in est:
        zeta = est["damping_ratio"].value if "damping_ratio" in est else None
        plant = prior.model_copy(update={"driveline": prior.driveline.model_copy(update=inertias)})
        k_a, d_a = axle_for(plant, ratio, est["resonance_Hz"].value, zeta)
        sets["driveline.k_a"] = k_a
        if d_a is not None:
            sets["driveline.d_a"] = d_a
    return sets
