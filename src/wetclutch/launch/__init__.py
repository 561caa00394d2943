"""Torque control of a launch from standstill: controllers, their design, the closed loop, metrics, verification.

``wetclutch.launch.simulate(params, "launch", wetclutch.launch.Conditions(t_ref=120, oil_temp_C=41))``
runs one launch (:mod:`~wetclutch.launch.loop`); :mod:`~wetclutch.launch.controller` holds
the compiled controllers, :mod:`~wetclutch.launch.design` their settings and design,
:mod:`~wetclutch.launch.metrics` the figures and requirements,
:mod:`~wetclutch.launch.verify` the Monte Carlo verification and
:mod:`~wetclutch.launch.campaign` the main job.
"""

from .loop import Conditions, LaunchResult, simulate

__all__ = ["Conditions", "LaunchResult", "simulate"]
