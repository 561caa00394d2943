# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # wetclutch, top to bottom
#
# From rig measurements to a verified launch controller, on small sizes so that it runs in
# a minute or two (after the one-off compilation of the numba core):
#
# 1. run experiments on the virtual test rig and write them as a real rig would,
# 2. identify the clutch from those files,
# 3. design the launch controller on the identified plant and launch with it,
# 4. verify it over the range of conditions,
# 5. look at the plots, and write the HTML reports.
#
# Open it as a notebook with `jupytext --to notebook examples/walkthrough.py`, or run it as a
# script: `python examples/walkthrough.py [OUT_DIR]` (default `out/walkthrough`).

# %%
import sys
from pathlib import Path

import matplotlib

if "ipykernel" not in sys.modules:
    matplotlib.use("Agg")  # as a script: plots go to files
import matplotlib.pyplot as plt

import wetclutch as wc
from wetclutch import ident
from wetclutch.launch import Conditions, design, simulate, verify
from wetclutch.report import identify as identify_report
from wetclutch.report import rig as rig_report
from wetclutch.report import verify as verify_report
from wetclutch.rig import experiments as rig

OUT = Path(sys.argv[1]) if len(sys.argv) > 1 and not sys.argv[1].startswith("-") else Path("out/walkthrough")
OUT.mkdir(parents=True, exist_ok=True)


def stacked(df, panels, path):
    """Signals of ``df`` over time, one panel per (label, columns, scale); saved to ``path``."""
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 2.4 * len(panels)), sharex=True)
    for ax, (label, cols, scale) in zip(axes, panels):
        for c in cols:
            ax.plot(df["time"], df[c] * scale, label=c)
        ax.set_ylabel(label)
        ax.legend(fontsize=7)
    axes[-1].set_xlabel("time [s]")
    fig.savefig(path)

# %% [markdown]
# ## 1. Rig experiments
#
# The "real" clutch here is the model with a friction curve and CVT ratio that differ from the
# defaults: identification has to find them. A torque step at 41 C on the clutch, and a pressure
# staircase on the valve alone (PWM input). Each run is written as `measured.csv`, `.mf4`, `.mat`
# with `meta.json`, as a rig would write it.

# %%
truth = wc.load_params(overrides={"friction.mu_slip_poly": [-1.2e-6, 2.2e-4, 3.0e-2], "driveline.ratio": 0.6})
runs = {
    "step41": rig.run("step", truth, level=1.5, oil_temp_C=41.0, seed=1),
    "stair": rig.run("staircase", truth, config="valve-only", input_mode="pwm", level=0.15, from_=0.0, seed=3),
}
for name, res in runs.items():
    rig_report.write(res, OUT / "rig" / name)
stacked(runs["step41"].measured, [("p [bar]", ["p_clutch"], 1e-5), ("T_r [N m]", ["T_r"], 1.0)], OUT / "step41.png")

# %% [markdown]
# ## 2. Identification
#
# Read the files back (any of the three formats), identify, and write `identified.json`,
# `params.toml` (loads with `--param-file`), `report.md` and `report.html`.

# %%
recs = [ident.load(OUT / "rig" / "step41" / "measured.mf4"), ident.load(OUT / "rig" / "stair" / "measured.csv")]
found = ident.identify(recs)
identify_report.write(found, OUT / "identify")
print("CVT ratio: identified", round(found.estimates["ratio"].value, 4), "true", truth.driveline.ratio)
print("mu(slip):", [f"{c:.3g}" for c in found.estimates["mu_slip_poly"].value])
plant = found.identified

# %% [markdown]
# ## 3. Design and launch
#
# The launch controller designed on the identified plant, then a launch with it on the *true*
# clutch (a request of 120 N m at 1 s).

# %%
ctrl = design.design(plant, "launch")
launch = simulate(truth, ctrl, Conditions(t_ref=120.0))
s = launch.summary
print(f"launch: steady-state error {s['steady_state_error_pct']:.2f} %, t95 {s['t95_s']:.3f} s, "
      f"requirements {s['requirements']}")
stacked(launch.signals, [("torque [N m]", ["t_ref", "T_r"], 1.0), ("p [bar]", ["p_clutch"], 1e-5),
                         ("u [V]", ["u"], 1.0)], OUT / "launch.png")

# %% [markdown]
# ## 4. Verification
#
# A few random samples of the ranges (`wetclutch verify` takes 1,000 and the corners), on one
# process. `verify.html` holds the interactive histograms and scatters: hover a point for its
# conditions and the command that replays it.

# %%
result = verify.run(ctrl, truth, n=4, seed=0, workers=1, corners=False, progress=False)
verify_report.write(result, OUT / "verify", ctrl)
print(f"verify: {result['cases']} launches, all requirements met in {100 * result['pass_rate']:.0f} %")
print("worst case replays with:", result["worst"][0]["replay"])

# %% [markdown]
# ## 5. What was written
#
# Open the `.html` files in a browser: they need no network and no other file.

# %%
for f in sorted(OUT.rglob("*.html")):
    print(f"{f}  {f.stat().st_size / 1e6:.2f} MB")
