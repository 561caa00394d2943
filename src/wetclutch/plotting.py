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


def plot_rig(measured: pd.DataFrame, truth: pd.DataFrame, path: Path, title: str) -> None:
    """A rig run: command, pressure, torque and speeds; measured (dots) over true (lines)."""
    panels = [("Command u", ["u"]), ("Clutch pressure [bar]", ["p_clutch"]), ("Torque T_r [N m]", ["T_r"]),
              ("Speeds [rad/s]", ["omega_p", "omega_1", "omega_s"])]
    panels = [(n, [c for c in cols if c in measured.columns]) for n, cols in panels]
    panels = [pc for pc in panels if pc[1]]
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels) + 0.6), sharex=True, squeeze=False)
    for ax, (name, cols) in zip(axes[:, 0], panels):
        scale = 1e-5 if "bar" in name else 1.0
        for c in cols:
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
