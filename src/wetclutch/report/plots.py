"""Plots of simulated signals (PNG, headless)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

#: panels per scenario: (title, y label, columns)
PANELS: dict[str, list[tuple[str, str, list[str]]]] = {
    "engage": [
        ("Speeds", "rad/s", ["omega_p", "omega_1", "omega_r", "omega_s"]),
        ("Torques", "N m", ["T_c", "T_r"]),
        ("Clutch capacity", "N m", ["T_cap", "T_c"]),
        ("Clutch plate temperature", "C", ["T_plate"]),
        ("Lock state", "-", ["locked", "brake_locked"]),
    ],
    "coupled-clutches": [
        ("Speeds", "rad/s", ["J1_w", "J2_w", "J3_w", "J4_w"]),
        ("Clutch torques", "N m", ["clutch1_tau", "clutch2_tau", "clutch3_tau"]),
        ("Lock state", "-", ["clutch1_locked", "clutch2_locked", "clutch3_locked"]),
    ],
}


def plot_signals(df: pd.DataFrame, scenario: str, path: Path, title: str | None = None) -> None:
    """Multi-panel time plot of ``df`` (column ``time``) for ``scenario``, saved to ``path``."""
    panels = PANELS[scenario]
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels) + 0.6), sharex=True)
    for ax, (name, unit, cols) in zip(axes, panels):
        for c in cols:
            if name.startswith("Lock"):
                ax.step(df["time"], df[c], where="post", label=c)
            else:
                ax.plot(df["time"], df[c], label=c, lw=1.2)
        ax.set_ylabel(unit)
        ax.set_title(name, fontsize=10, loc="left")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, ncol=len(cols))
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(title or scenario)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_rig(measured: pd.DataFrame, truth: pd.DataFrame, path: Path, title: str, u_unit: str | None = None) -> None:
    """A rig run: command, pressure, torque and speeds; measured (dots) over true (lines). ``u_unit``: the
    command's unit (V or duty)."""
    panels = [(f"Command u [{u_unit}]" if u_unit else "Command u", ["u"]), ("Clutch pressure [bar]", ["p_clutch"]),
              ("Torque T_r [N m]", ["T_r"]), ("Speeds [rad/s]", ["omega_p", "omega_1", "omega_s"])]
    panels = [(n, [c for c in cols if c in measured.columns]) for n, cols in panels]
    if "T_plate" in truth.columns:
        panels.append(("Clutch plate temperature [C]", ["T_plate"]))
    panels = [pc for pc in panels if pc[1]]
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels) + 0.6), sharex=True, squeeze=False)
    for ax, (name, cols) in zip(axes[:, 0], panels):
        scale = 1e-5 if "bar" in name else 1.0
        for c in cols:
            if c in measured.columns:
                ax.plot(measured["time"], measured[c] * scale, ".", ms=1.5, alpha=0.5, label=f"{c} measured")
            ax.plot(truth["time"], truth[c] * scale, lw=1.0, label=f"{c} true")
        ax.set_title(name, fontsize=10, loc="left")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=2)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_launch(signals: pd.DataFrame, truth: pd.DataFrame, summary: dict, path: Path, extra: pd.DataFrame | None = None,
                extra_label: str = "baseline", extra_summary: dict | None = None) -> None:
    """A launch: request and axle torque, pressure, valve input, speeds, plate temperature (``extra``: a second
    launch to compare).

    Parameters
    ----------
    signals, truth
        The launch's measured and true signals.
    summary
        Its figures: the controller, oil temperature, request and verdicts name the plot.
    path
        The PNG written.
    extra
        The measured signals of a second launch, drawn in the panels of torque, pressure and valve input.
    extra_label
        What the second launch is.
    extra_summary
        The second launch's figures: its verdicts go into the title beside the first's.
    """
    heat = "T_plate" in truth.columns
    fig, axes = plt.subplots(5 if heat else 4, 1, figsize=(9, 11 if heat else 9), sharex=True)
    name = summary.get("controller", "")
    # one colour per launch in every panel (and the true torque in a third): the default colour cycle would give the
    # second launch another colour in the torque panel, where the true torque comes first, than in the others
    mine, theirs, true = "tab:blue", "tab:orange", "tab:green"
    t = signals["time"]
    ax = axes[0]
    ax.plot(t, signals["t_ref"], "k--", lw=1.2, label="request t_ref")
    ax.plot(t, signals["T_r"], lw=0.8, color=mine, label=f"T_r measured, {name}")
    ax.plot(truth["time"], truth["T_r"], lw=1.0, alpha=0.8, color=true, label=f"T_r true, {name}")
    if extra is not None:
        ax.plot(extra["time"], extra["T_r"], lw=0.8, alpha=0.8, color=theirs, label=f"T_r measured, {extra_label}")
    ax.set_title("Axle torque [N m]", fontsize=10, loc="left")
    axes[1].plot(t, signals["p_clutch"] * 1e-5, lw=0.8, color=mine, label=f"p_clutch measured, {name}")
    if extra is not None:
        axes[1].plot(extra["time"], extra["p_clutch"] * 1e-5, lw=0.8, alpha=0.8, color=theirs,
                     label=f"p_clutch measured, {extra_label}")
    axes[1].set_title("Clutch pressure [bar]", fontsize=10, loc="left")
    axes[2].plot(t, signals["u"], lw=0.8, color=mine, label=f"u, {name}")
    if extra is not None:
        axes[2].plot(extra["time"], extra["u"], lw=0.8, alpha=0.8, color=theirs, label=f"u, {extra_label}")
    axes[2].set_title("Valve input [V]", fontsize=10, loc="left")
    # colours of their own: orange and green stand for the second launch and the true torque above
    for c, colour in (("omega_p", "tab:blue"), ("omega_1", "tab:purple"), ("omega_s", "tab:brown")):
        axes[3].plot(t, signals[c], lw=0.8, color=colour, label=f"{c}, {name}")
    axes[3].set_title("Speeds [rad/s]", fontsize=10, loc="left")
    if heat:
        axes[4].plot(truth["time"], truth["T_plate"], lw=1.0, label="T_plate true")
        if summary.get("T_plate_limit_C") is not None:
            axes[4].axhline(summary["T_plate_limit_C"], color="r", ls="--", lw=0.8, label="limit")
        axes[4].set_title("Clutch plate temperature [C]", fontsize=10, loc="left")
    for a in axes:
        a.grid(True, alpha=0.3)
        # where the lines leave room: in the upper right the legend hid the torque's steady level
        a.legend(loc="best", fontsize=7, ncol=2)
    axes[-1].set_xlabel("time [s]")
    req = summary.get("requirements", {})
    # the launch's conditions and whose verdicts these are: the PNG is shared on its own, without the report's text
    what = ", ".join(f for f in (f"{name} controller" if name else "",
                                 f"oil {summary['oil_temp_C']:g} C" if summary.get("oil_temp_C") is not None else "",
                                 f"request {summary['t_ref_Nm']:g} N m" if summary.get("t_ref_Nm") is not None else "")
                     if f)
    verdicts = ", ".join(f"{k} {'pass' if v else 'FAIL'}" for k, v in req.items())
    title = "launch" + (f" ({what})" if what else "")
    if verdicts:
        title += f"\n{name + ': ' if name else ''}{verdicts}"
    if extra is not None and extra_summary and extra_summary.get("requirements"):
        title += f"\n{extra_label}: " + ", ".join(f"{k} {'pass' if v else 'FAIL'}"
                                                  for k, v in extra_summary["requirements"].items())
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
