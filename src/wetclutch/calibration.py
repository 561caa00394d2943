"""Calibration of the default rig against the study's figures (spec section 6).

Each figure is reproduced by its own virtual experiment, as the study measured it:

* contact pressure: the pressure at torque onset after a command step;
* dead time: command step (PWM, from 0) to torque onset, at 41 C and 85 C, for
  pdc 0.05 and pdc 0.2 (the study's "pdc >= 0.1" cell);
* whole clutch static pressure vs DC input at 85 C, 1 to 4 V;
* valve alone (restriction passing 32 l/min) static pressure vs duty cycle, up and
  down staircases, pdc 0.1 to 0.35;
* whole clutch static pressure vs oil temperature at pdc 0.2, 20 to 85 C;
* driveline resonance after synchronisation.

:func:`run` returns the figures with published value, simulated value, error and
pass/fail; :func:`write_report` writes ``report.md``, ``report.json`` and overlay plots.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import clutch, driveline
from .scenarios import simulate
from .network import integrate
from .onset import TORQUE_ONSET, first_crossing
from .params import Params
from .signals import Step, Table


@dataclass
class Figure:
    """One published figure and its simulated counterpart."""

    name: str
    published: Any
    simulated: Any
    error: float  # relative (or absolute where ``unit`` says so)
    tolerance: float
    error_kind: str = "relative"
    unit: str = ""
    note: str = ""
    curve: dict[str, list[float]] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return bool(np.isfinite(self.error) and abs(self.error) <= self.tolerance)


def _settled(p: Params, u, pwm: bool, config: str, temp: float, t_end: float, window: float = 1.0) -> float:
    rn = clutch.build(p, u, pwm=pwm, config=config, temp_C=temp)
    tr = integrate(rn.network, t_end, dt_out=1e-3)
    return float(np.mean(tr.x[tr.t > t_end - window, rn.i_pressure]))


def onset(p: Params, duty: float, temp: float, t_end: float = 3.0) -> tuple[float, float]:
    """(dead time s, pressure Pa at onset) for a PWM step from 0 to ``duty`` at ``T_STEP``."""
    rn = clutch.build(p, Step(1.0, 0.0, duty), pwm=True, temp_C=temp)
    tr = integrate(rn.network, t_end, dt_out=1e-4)
    crossing = first_crossing(tr.t, np.abs(tr.clutch_torque("clutch")), TORQUE_ONSET)
    if crossing is None:
        return np.nan, np.nan
    # the pressure between the two samples that straddle the onset (it rises steeply there)
    t_on, k, f = crossing
    p_on = tr.x[k - 1, rn.i_pressure] + f * (tr.x[k, rn.i_pressure] - tr.x[k - 1, rn.i_pressure])
    return float(t_on - 1.0), float(p_on)


def staircase(p: Params, duties: np.ndarray, temp: float = 85.0, dwell: float = 1.5) -> tuple[np.ndarray, np.ndarray]:
    """Valve-only static pressure (Pa) at each duty, going up then down (hysteresis)."""
    levels = np.concatenate([duties, duties[::-1]])
    t = 1.0 + dwell * np.arange(levels.size)
    tt = np.concatenate([[0.0], np.ravel(np.column_stack([t, t + 1e-3]))])
    vv = np.concatenate([[0.0], np.ravel(np.column_stack([np.concatenate([[0.0], levels[:-1]]), levels]))])
    rn = clutch.build(p, Table(tt, vv, kinks_are_breakpoints=True), pwm=True, config="valve-only", temp_C=temp)
    tr = integrate(rn.network, float(t[-1] + dwell), dt_out=1e-3)
    pk = np.array([np.mean(tr.x[(tr.t > tk + dwell - 0.5) & (tr.t < tk + dwell), rn.i_pressure]) for tk in t])
    return pk[: duties.size], pk[duties.size :][::-1]


def run(params: Params | None = None) -> list[Figure]:
    """All calibration figures for ``params`` (the defaults if None)."""
    p = params if params is not None else Params()
    figs: list[Figure] = []

    dt85, p_on = onset(p, 0.2, 85.0)
    figs.append(Figure("contact pressure (torque onset)", 0.7, p_on / 1e5, p_on / 1e5 - 0.7, 0.1, "absolute", "bar"))
    for duty, temp, pub in ((0.05, 41.0, 0.50), (0.05, 85.0, 0.35), (0.2, 41.0, 0.20), (0.2, 85.0, 0.10)):
        dt = dt85 if (duty, temp) == (0.2, 85.0) else onset(p, duty, temp)[0]
        figs.append(Figure(f"dead time pdc {duty:g} at {temp:g} C", pub, dt, dt / pub - 1.0, 0.2, unit="s"))

    v = np.linspace(1.0, 4.0, 7)
    sim = np.array([_settled(p, Step(1.0, 0.2, x), False, "clutch", 85.0, 4.0) for x in v]) / 1e5
    pub = 0.41 * v**2 + 0.29 * v + 0.20
    err = sim / pub - 1.0
    figs.append(Figure("whole clutch static p vs DC input, 85 C (1..4 V)", pub.round(3).tolist(), sim.round(3).tolist(),
                       float(err[np.argmax(np.abs(err))]), 0.1, unit="bar",
                       curve={"v": v.tolist(), "published": pub.tolist(), "simulated": sim.tolist()}))

    d = np.linspace(0.1, 0.35, 6)
    up, down = staircase(p, d)
    pub = 24.0 * d - 1.38
    mid = 0.5 * (up + down) / 1e5
    err = mid / pub - 1.0
    width = float(np.max(np.abs(up - down)) / 1e5)
    figs.append(Figure("valve alone static p vs duty cycle (pdc 0.1..0.35)", pub.round(3).tolist(), mid.round(3).tolist(),
                       float(err[np.argmax(np.abs(err))]), 0.1, unit="bar",
                       note=f"hysteresis (largest up-down difference) {width:.3f} bar",
                       curve={"pdc": d.tolist(), "published": pub.tolist(), "up": (up / 1e5).tolist(),
                              "down": (down / 1e5).tolist()}))
    figs.append(Figure("valve hysteresis visible (up vs down staircase)", "visible", round(width, 3),
                       0.0 if width > 0.02 else np.inf, 0.0, "absolute", "bar"))

    temps = np.array([20.0, 41.0, 60.0, 85.0])
    sim = np.array([_settled(p, Step(1.0, 0.0, 0.2), True, "clutch", T, 4.0) for T in temps]) / 1e5
    pub = 4.8e-4 * temps**2 + 4.1e-4 * temps + 4.2
    err = sim / pub - 1.0
    figs.append(Figure("whole clutch static p vs oil temperature at pdc 0.2 (20..85 C)", pub.round(3).tolist(),
                       sim.round(3).tolist(), float(err[np.argmax(np.abs(err))]), 0.1, unit="bar",
                       curve={"T": temps.tolist(), "published": pub.tolist(), "simulated": sim.tolist()}))
    eng = simulate("engage", p)
    after = eng.signals[eng.signals.time > (eng.summary["t_sync"] or 0.0) + 0.2]
    f_ring = driveline.ring_frequency(after.time.to_numpy(), after.T_r.to_numpy())
    figs.append(Figure("driveline resonance after synchronisation", 2.1, f_ring, f_ring / 2.1 - 1.0, 0.03, unit="Hz"))
    return figs


EXPLANATIONS = {
    "valve alone": (
        "The valve's metering port is sized by the clutch fill: with it, the fill at pdc >= 0.1 takes the study's "
        "0.1 s at 85 C and 0.2 s at 41 C. Passing the valve test's 32 l/min at the study's valve-only pressures "
        "needs about four times that port area (run with `--set valve.port_width=0.048`: the valve-only curve rises "
        "to 2-7 bar) but then the clutch fills in 0.066 s at 85 C. One port cannot give both; the report keeps the "
        "fill (dead time) figures, which matter for control. Moving the flow-limiting restriction into the "
        "clutch installation's feed (`--set valve.port_width=0.038 --set valve.x_port=0.0011 --set "
        "hydraulics.feed_orifice=1.33e-5`) and adding the steady flow force (`--set valve.flow_force=1`) "
        "brings the valve-only curve to within 46 % (0.9 to 6.3 bar) but costs the pdc 0.05 dead time at 41 C "
        "(-27 %) and the DC curve (+15 %); a Nelder-Mead search over these six parameters found no set that "
        "meets all figures."
    ),
    "hysteresis": (
        "The stem friction (0.1 N, about 0.05 bar of feedback force) is dithered out by the PWM ripple, and on the "
        "valve test the stem sits against the fully open port, so up and down staircases coincide."
    ),
    "temperature": (
        "In the model the static pressure of a dead-end volume is set by the force balance on the stem, which does "
        "not depend on viscosity; at pdc 0.2 it is near the supply pressure at every temperature. The study's 4.4 bar "
        "at 20 C would need the valve to be flow-limited in steady state (for example a stem that follows the PWM "
        "pulses, so that the viscous feed and the turbulent drain share each period); the default PWM frequency and "
        "stem dynamics do not produce that. A continuous turbulent leakage through the rotating seal rings does: "
        "with `--set hydraulics.leak_orifice=3e-8` the valve, wide open at pdc 0.2, loses 3.5 bar in the viscous "
        "feed line at 20 C and 0.4 bar at 85 C (5.0 to 7.2 bar over 20..85 C), but the leak then delays the fill "
        "at small inputs (pdc 0.05 dead time at 85 C +29 %) and raises the pressure at torque onset to 0.86 bar."
    ),
}


def _explain(name: str) -> str:
    for key, text in EXPLANATIONS.items():
        if key in name:
            return text
    return ""


def write_report(figs: list[Figure], out: str | Path) -> None:
    """``report.md``, ``report.json`` and overlay plots for the figures, written atomically into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .output import atomic_dir, write_json

    with atomic_dir(out) as d:
        rows = []
        for f in figs:
            rows.append({
                "figure": f.name, "published": f.published, "simulated": f.simulated, "error": f.error,
                "error_kind": f.error_kind, "tolerance": f.tolerance, "unit": f.unit, "pass": f.passed,
                "note": f.note, "explanation": "" if f.passed else _explain(f.name),
            })
        write_json(d / "report.json", {"figures": rows, "passed": sum(r["pass"] for r in rows), "total": len(rows)})
        lines = ["# Calibration of the default rig against the study (WFW 96.071)", "",
                 f"{sum(r['pass'] for r in rows)} of {len(rows)} figures within tolerance.", "",
                 "| figure | published | simulated | error | tolerance | result |", "|---|---|---|---|---|---|"]

        def fmt(v: Any) -> str:
            if isinstance(v, float):
                return f"{v:.3f}"
            if isinstance(v, list):
                return ", ".join(f"{x:.2f}" for x in v)
            return str(v)

        for r in rows:
            err = f"{100 * r['error']:+.1f} %" if r["error_kind"] == "relative" else f"{r['error']:+.3f} {r['unit']}"
            tol = f"{100 * r['tolerance']:.0f} %" if r["error_kind"] == "relative" else f"{r['tolerance']} {r['unit']}"
            lines.append(f"| {r['figure']} | {fmt(r['published'])} | {fmt(r['simulated'])} | {err} | {tol} | "
                         f"{'pass' if r['pass'] else 'FAIL'} |")
        lines.append("")
        for r in rows:
            if r["note"]:
                lines.append(f"* {r['figure']}: {r['note']}")
        failed = [r for r in rows if not r["pass"] and r["explanation"]]
        if failed:
            lines += ["", "## Why some figures are not met", ""]
            for r in failed:
                lines += [f"**{r['figure']}.** {r['explanation']}", ""]
        lines += ["", "![static curves](curves.png)", "", "![dead times](dead_times.png)", ""]
        (d / "report.md").write_text("\n".join(lines))

        curves = [f for f in figs if f.curve]
        fig, axes = plt.subplots(1, len(curves), figsize=(4.5 * len(curves), 3.6), squeeze=False)
        for ax, f in zip(axes[0], curves):
            c = f.curve
            xkey = next(iter(c))
            ax.plot(c[xkey], c["published"], "k--", label="study (fit)")
            for k in ("simulated", "up", "down"):
                if k in c:
                    ax.plot(c[xkey], c[k], "o-", ms=3, label=f"model {k}" if k != "simulated" else "model")
            ax.set_xlabel(xkey)
            ax.set_ylabel("p [bar]")
            ax.set_title(f.name, fontsize=8)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(d / "curves.png", dpi=110)
        plt.close(fig)

        dts = [f for f in figs if f.name.startswith("dead time")]
        fig, ax = plt.subplots(figsize=(6, 3.2))
        x = np.arange(len(dts))
        ax.bar(x - 0.2, [f.published for f in dts], 0.4, label="study")
        ax.bar(x + 0.2, [f.simulated for f in dts], 0.4, label="model")
        ax.set_xticks(x, [f.name.replace("dead time ", "") for f in dts], fontsize=8)
        ax.set_ylabel("dead time [s]")
        ax.legend()
        fig.tight_layout()
        fig.savefig(d / "dead_times.png", dpi=110)
        plt.close(fig)
