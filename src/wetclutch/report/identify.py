"""Outputs of an identification: ``identified.json``, ``params.toml``, ``report.md`` and its plots.

:func:`write` puts them into one directory, atomically (all or nothing).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import params as params_mod
from ..ident.dynamics import MODEL_NAMES
from ..ident.estimate import BAR
from ..ident.result import PARAMS_FROM, Identification
from ..ident.validation import STEP_VAF_MIN
from ..output import atomic_dir, write_json
from . import html
from .plots import plt
from .text import plural

def write(result: Identification, out: str | Path) -> None:
    """Write ``identified.json``, ``params.toml``, ``report.md`` and the plots into ``out`` (replaced whole)."""
    with atomic_dir(out) as d:
        write_json(d / "identified.json", result.as_json())
        (d / "params.toml").write_text(_params_toml(result))
        plots = _plots(result, d)
        md = _report(result, plots)
        (d / "report.md").write_text(md)
        html.write_identify(d / "report.html", md, result)


def _changed(result: Identification) -> list[tuple[str, Any, Any]]:
    prior = {p: v for p, v, *_ in params_mod.describe(result.prior)}
    return [(p, prior[p], v) for p, v, *_ in params_mod.describe(result.identified) if v != prior[p]]


def _params_toml(result: Identification) -> str:
    head = ["# Identified by `wetclutch identify` from:"]
    head += [f"#   {r.path}" for r in result.recordings]
    head += ["# Changed from the prior parameters:"]
    head += [f"#   {p}: {_fmt(a)} -> {_fmt(b)}" for p, a, b in _changed(result)] or ["#   (none)"]
    return "\n".join(head) + "\n" + params_mod.to_toml(result.identified)


def _fmt(v: Any) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    if isinstance(v, float):
        return f"{v:.5g}"
    return str(v)


def _pm(value: Any, se: Any) -> str:
    if isinstance(value, dict):
        return ", ".join(f"{k} {_pm(v, (se or {}).get(k))}" for k, v in value.items())
    if isinstance(value, list):
        ses = se if isinstance(se, list) else [None] * len(value)
        return "[" + ", ".join(_pm(v, s) for v, s in zip(value, ses)) + "]"
    return f"{value:.5g}" + (f" ± {se:.2g}" if isinstance(se, float) and np.isfinite(se) else "")


def measured_cell(value: float, se: float, digits: int) -> str:
    """A table cell for a value measured on one run and its standard error: a dash where the run did not show
    it (NaN), no error where none could be given."""
    if not np.isfinite(value):
        return "–"
    return f"{value:.{digits}f}" + (f" ± {se:.1g}" if np.isfinite(se) else "")


#: what the report says when the clutch output's inertia comes from the prior
J1_FROM_PRIOR = (
    "The clutch output and CVT input inertia (`driveline.J_1`) is the prior's. These runs cannot show it: unless it "
    "is heavy, the axle's damper makes its mode overdamped, and in the slip phase it takes a negligible share of the "
    "clutch torque. In a launch it matters: at CVT ratio `i` a heavier clutch output rings against the axle at "
    "`f = sqrt(k_a i^2 / J_1) / (2 pi)`. The launch controller measures it in the slip phase (a heavy one within its "
    "first launch) and keeps it in its adaptation state. A verification on these parameters varies the prior's "
    "value by the ranges' spread; if the clutch output is known to be heavier, set `driveline.J_1` (`--set`) for "
    "`verify` and `report`.")


def _report(result: Identification, plots: list[tuple[str, str]]) -> str:
    e = result.estimates
    lines = ["# Identification report", "", "## Files", "", "| file | experiment | config | input | oil temp [C] | duration [s] |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {r.path} | {r.experiment} | {r.config} | {r.input_mode} | {r.oil_temp_C:.1f} | {r.t[-1] - r.t[0]:.1f} |"
              for r in result.recordings]
    lines += ["", "## Identified values (± one standard error)", "", "| quantity | value | unit | from |", "|---|---|---|---|"]
    for name, est in e.items():
        files = sorted({s["file"] for s in est.sources})
        lines.append(f"| {name} | {_pm(est.value, est.se)} | {est.unit} | {plural(len(files), 'file')} |")
    if result.onsets:
        lines += ["", "### Dead time and contact pressure per run", "",
                  "| file | oil temp [C] | input | dead time [s] | stroke start [bar] | contact pressure [bar] |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {o.rec.path} | {o.rec.oil_temp_C:.1f} | {o.level:g} | {measured_cell(o.dead_time, o.dead_time_se, 4)} | "
                  f"{measured_cell(o.p_start / BAR, o.p_start_se / BAR, 3)} | "
                  f"{measured_cell(o.p_contact / BAR, o.p_contact_se / BAR, 3)} |" for o in result.onsets]
    if result.steps:
        lines += ["", "### Pressure models fitted to steps and relaxations", "",
                  f"A model whose VAF is {STEP_VAF_MIN:g} % or less does not describe its step (a fill and the plates' "
                  "contact are no low-order lag): shown, not used; its parameters mean little.", "",
                  "| file | model | gain [bar/unit] | dead time [s] | parameters | VAF [%] |", "|---|---|---|---|---|---|"]
        lines += step_rows(result.steps)
    if result.responses:
        lines += ["", "### Frequency response (command to pressure)", "",
                  "| file | band [Hz] | fitted gain [bar/unit] | dead time [s] | omega_n [rad/s] | zeta |", "|---|---|---|---|---|---|"]
        for r in result.responses:
            mp = r.model_params
            lines.append(f"| {r.rec.path} | {r.freq[0]:.2f}..{r.freq[-1]:.2f} | {mp['gain_bar_per_unit']:.4g} | "
                         f"{mp['dead_time_s']:.4f} | {mp['omega_n_rad_s']:.4g} | {mp['zeta']:.3g} |")
    lines += ["", "## Parameters: identified or from the prior", "",
              "The parameters that identification determines when the runs allow it; every other parameter "
              "(valve, hydraulics but the prestress, the contact travel and the supply pressure, thermal, ...) comes "
              "from the prior parameters, which these experiments do not determine.", "",
              "| parameter | source | reason |", "|---|---|---|"]
    sources = result.sources()
    lines += [f"| {p} | {status} | {why} |" for p, (status, why) in sources.items()]
    if sources["driveline.J_1"][0] != "identified":
        lines += ["", J1_FROM_PRIOR]
    lines += ["", "## Identified versus prior parameters", "", "| parameter | prior | identified | from |", "|---|---|---|---|"]
    origin = {p: PARAMS_FROM[p] if status == "identified" else "not identified (see above)"
              for p, (status, _) in sources.items()}
    lines += [f"| {p} | {_fmt(a)} | {_fmt(b)} | {origin.get(p, '')} |"
              for p, a, b in _changed(result)] or ["| (none) | | | |"]
    lines += ["", "## Validation on held-out files", "",
              "Each file predicted by models identified from the other files (leave one file out).", "",
              "| file | signal | model | NRMSE | VAF [%] |", "|---|---|---|---|---|"]
    lines += [f"| {v['file']} | {v['signal']} | {v['model']} | {v['nrmse']:.3f} | {v['vaf_percent']:.1f} |"
              for v in result.validation] or ["| (too few files of a kind) | | | | |"]
    lines += ["", "## Plots", ""]
    lines += [f"![{title}]({name})" for name, title in plots]
    return "\n".join(lines) + "\n"


def step_rows(steps: list) -> list[str]:
    """The table rows of the step models: a model that does not describe its step (VAF at most
    :data:`~wetclutch.ident.validation.STEP_VAF_MIN`) says so in its VAF cell."""
    rows = []
    for m in steps:
        par = ", ".join(f"{k} {v:.4g}" for k, v in m.params.items())
        vaf = f"{m.vaf:.1f}" + (" (poor fit: not used)" if not m.vaf > STEP_VAF_MIN else "")
        rows.append(f"| {m.rec.path} | {MODEL_NAMES[m.order]} | {m.gain / BAR:.4g} | {m.theta:.4f} | {par} | {vaf} |")
    return rows


def _save(fig: plt.Figure, path: Path) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def _plots(result: Identification, d: Path) -> list[tuple[str, str]]:
    made: list[tuple[str, str]] = []
    e = result.estimates
    if result.slips and "mu_slip_poly" in e:
        fig, (ax, rx) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, height_ratios=[3, 1])
        coef = np.array(e["mu_slip_poly"].value)
        for s in result.slips:
            k = slice(None, None, max(1, s.slip.size // 2000))
            ax.plot(s.slip[k], s.mu[k], ".", ms=2, alpha=0.4, label=f"{s.rec.path.parent.name}/{s.rec.path.name}")
            rx.plot(s.slip[k], (s.mu - np.polyval(coef, s.slip))[k], ".", ms=2, alpha=0.4)
        w = np.linspace(0.0, max(s.slip.max() for s in result.slips), 200)
        ax.plot(w, np.polyval(coef, w), "k-", lw=2, label="identified")
        ax.plot(w, np.polyval(result.prior.friction.mu_slip_poly, w) * result.prior.friction.mu_scale, "k--", label="prior")
        ax.set_ylabel("mu [m]")
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
        rx.set_ylabel("residual [m]")
        rx.set_xlabel("slip [rad/s]")
        rx.grid(True, alpha=0.3)
        _save(fig, d / "friction.png")
        made.append(("friction.png", "friction versus slip: samples, fit, prior, residuals"))
    if result.onsets:
        fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
        for o in result.onsets:
            t = o.rec.t - o.t_command
            w = (t > o.dead_time - 0.15) & (t < o.dead_time + 0.05)
            line = axes[0].plot(t[w], o.rec.data["p_clutch"][w] / BAR, lw=1, label=f"{o.rec.oil_temp_C:.0f} C, {o.level:g}")
            axes[0].plot([o.dead_time], [o.p_contact / BAR], "o", color=line[0].get_color())
            axes[1].plot(t[w], o.rec.data["T_r"][w], lw=1, color=line[0].get_color())
            axes[1].axvline(o.dead_time, color=line[0].get_color(), ls=":")
        axes[0].set_ylabel("p [bar]")
        axes[0].set_ylim(0, 3)
        axes[0].legend(fontsize=7)
        axes[1].set_ylabel("T_r [N m]")
        axes[1].set_xlabel("time after the command step [s]")
        for ax in axes:
            ax.grid(True, alpha=0.3)
        _save(fig, d / "onset.png")
        made.append(("onset.png", "torque onset: dead time and contact pressure"))
    if result.steps:
        fig, (ax, rx) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, height_ratios=[3, 1])
        for m in result.steps:
            t, y, fit = m.fit
            if m.order == 1:
                ax.plot(t - m.t0, y / BAR, lw=0.8, alpha=0.6, label=f"{m.rec.path.parent.name} measured")
            ax.plot(t - m.t0, fit / BAR, lw=1, ls=["-", "--", ":"][m.order - 1], label=f"order {m.order}")
            rx.plot(t - m.t0, (y - fit) / BAR, lw=0.6)
        ax.set_ylabel("p [bar]")
        ax.legend(fontsize=6, ncol=2)
        rx.set_ylabel("residual [bar]")
        rx.set_xlabel("time after the command change [s]")
        for a in (ax, rx):
            a.grid(True, alpha=0.3)
        _save(fig, d / "steps.png")
        made.append(("steps.png", "pressure step models: fit overlays and residuals"))
    if result.responses:
        fig, (mx, px) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        for r in result.responses:
            f = r.freq
            mag = np.abs(r.H) / BAR
            mx.errorbar(f, mag, yerr=mag * r.rel_se, fmt=".", ms=3, label=f"{r.rec.path.parent.name} measured")
            model = r.model_response(f)
            mx.plot(f, np.abs(model) / BAR, "-", label="fitted model")
            px.plot(f, np.degrees(np.unwrap(np.angle(r.H))), ".", ms=3)
            px.plot(f, np.degrees(np.unwrap(np.angle(model))), "-")
        mx.set_xscale("log")
        mx.set_yscale("log")
        mx.set_ylabel("|p/u| [bar/unit]")
        mx.legend(fontsize=7)
        px.set_ylabel("phase [deg]")
        px.set_xlabel("frequency [Hz]")
        for a in (mx, px):
            a.grid(True, which="both", alpha=0.3)
        _save(fig, d / "bode.png")
        made.append(("bode.png", "frequency response command to pressure (Bode)"))
    if result.plateaus:
        fig, ax = plt.subplots(figsize=(8, 4))
        groups = sorted({(q.rec.config, q.rec.input_mode) for q in result.plateaus})
        for g in groups:
            pts = [q for q in result.plateaus if (q.rec.config, q.rec.input_mode) == g]
            for direction, marker in (("up", "^"), ("down", "v"), ("first", "o")):
                sel = [q for q in pts if q.direction == direction]
                if sel:
                    ax.plot([q.u for q in sel], [q.p / BAR for q in sel], marker, ls="none", label=f"{g[0]} {g[1]} {direction}")
        for key, est in e.items():
            if key.startswith(("valve_gain_poly", "clutch_gain_poly")):
                u = np.array([pt[0] for pt in est.extra["points"]])
                uu = np.linspace(u.min(), u.max(), 50)
                ax.plot(uu, np.polyval(est.value, uu), "-", label=f"{key} fit")
        ax.set_xlabel("command (V or duty)")
        ax.set_ylabel("static p [bar]")
        ax.legend(fontsize=6)
        ax.grid(True, alpha=0.3)
        _save(fig, d / "static.png")
        made.append(("static.png", "static pressure versus command, up and down (hysteresis)"))
    if result.ringings:
        fig, (ax, rx) = plt.subplots(2, 1, figsize=(8, 5), sharex=True, height_ratios=[3, 1])
        for r in result.ringings:
            t, y, fit = r.fit
            ax.plot(t - t[0], y, lw=0.8, label=f"{r.rec.path.parent.name} {r.freq:.3f} Hz, zeta {r.zeta:.3f}")
            ax.plot(t - t[0], fit, "k--", lw=0.8)
            rx.plot(t - t[0], y - fit, lw=0.6)
        ax.set_ylabel("T_r [N m]")
        ax.legend(fontsize=7)
        rx.set_ylabel("residual [N m]")
        rx.set_xlabel("time after synchronisation + 0.1 s [s]")
        for a in (ax, rx):
            a.grid(True, alpha=0.3)
        _save(fig, d / "resonance.png")
        made.append(("resonance.png", "ring-out after synchronisation: damped sinusoid fit"))
    if result.validation:
        torque = [v for v in result.validation if v["signal"] == "T_r"]
        pressure = [v for v in result.validation if v["signal"] == "p_clutch"]
        fig, axes = plt.subplots(2, 1, figsize=(8, 6), squeeze=False)
        for v in torque:
            tr = v["trace"]
            line = axes[0, 0].plot(tr["slip"], tr["measured"], ".", ms=1.5, alpha=0.4)
            order = np.argsort(tr["slip"])
            axes[0, 0].plot(tr["slip"][order], tr["predicted"][order], "-", lw=1, color=line[0].get_color())
        axes[0, 0].set_xlabel("slip [rad/s]")
        axes[0, 0].set_ylabel("T_r [N m] (dots measured, lines predicted)")
        for v in pressure:
            tr = v["trace"]
            line = axes[1, 0].plot(tr["time"], tr["measured"] / BAR, lw=0.6, alpha=0.6)
            axes[1, 0].plot(tr["time"], tr["predicted"] / BAR, "--", lw=1, color=line[0].get_color())
        axes[1, 0].set_xlabel("time [s]")
        axes[1, 0].set_ylabel("p [bar] (solid measured, dashed predicted)")
        for a in axes[:, 0]:
            a.grid(True, alpha=0.3)
        _save(fig, d / "validation.png")
        made.append(("validation.png", "validation on held-out files"))
    return made
