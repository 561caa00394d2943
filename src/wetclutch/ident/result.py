"""The result of an identification and the parameter set it implies."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import WetclutchError
from ..params import OIL_TEMP_RANGE_C, Params, describe, load
from ..plant.driveline import axle_for
from .dynamics import FrequencyResponse, StepModel
from .estimate import Estimate, source
from .friction import SlipSamples
from .onset import Onset
from .recordings import Recording
from .ringing import Ringing
from .static import Plateau

#: entries of ``identified.json`` that are always written (null when the files do not support them)
REPORTED = ("mu_slip_poly", "contact_pressure_Pa", "valve_gain", "clutch_gain_poly_bar_per_V", "resonance_Hz",
            "damping_ratio")


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
    validation: list[dict[str, Any]]
    identified: Params

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
        for key in REPORTED:  # always present, so that a reader can tell "not identified" from a typo
            out.setdefault(key, {"value": None, "se": None, "note": "not identified: no suitable runs", "sources": []})
        return out


def identified_params(prior: Params, est: dict[str, Estimate]) -> Params:
    """The prior parameters with the identified values put in (:func:`identified_values`)."""
    try:
        return load(None, identified_values(prior, est), base=prior)
    except WetclutchError as err:
        raise WetclutchError(f"identified values make no valid parameter set: {err}") from None


def identified_values(prior: Params, est: dict[str, Estimate]) -> dict[str, Any]:
    """Dotted parameter path -> identified value, for the parameters the estimates determine.

    ``friction.mu_slip_poly`` (``mu_scale`` 1), ``driveline.ratio``, ``rig.oil_temp_C``,
    ``hydraulics.x_contact`` (from the contact pressure, keeping the prior prestress,
    spring and piston area), ``driveline.k_a`` and ``d_a`` (from resonance and damping
    with the prior inertias, the relation in :mod:`wetclutch.params`).
    """
    sets: dict[str, Any] = {}
    if "mu_slip_poly" in est:
        sets["friction.mu_slip_poly"] = list(est["mu_slip_poly"].value)
        sets["friction.mu_scale"] = 1.0
        sets["friction.mu_slope"] = 1.0
    ratio = est["ratio"].value if "ratio" in est else prior.driveline.ratio
    if "ratio" in est:
        sets["driveline.ratio"] = ratio
    if "oil_temp_C" in est:
        sets["rig.oil_temp_C"] = float(np.clip(est["oil_temp_C"].value, *OIL_TEMP_RANGE_C))
    h = prior.hydraulics
    if "contact_pressure_Pa" in est and est["contact_pressure_Pa"].value > h.p_prestress:
        sets["hydraulics.x_contact"] = (est["contact_pressure_Pa"].value - h.p_prestress) * h.A_p / h.k_reset
    if "resonance_Hz" in est:
        zeta = est["damping_ratio"].value if "damping_ratio" in est else None
        k_a, d_a = axle_for(prior, ratio, est["resonance_Hz"].value, zeta)
        sets["driveline.k_a"] = k_a
        if d_a is not None:
            sets["driveline.d_a"] = d_a
    return sets
