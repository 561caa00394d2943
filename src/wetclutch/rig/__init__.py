"""The virtual test rig: experiments, the sensor chain, measurement files and the calibration figures.

``wetclutch.rig.run("step", input_mode="pwm", level=0.2, oil_temp_C=41)`` runs an
experiment (:mod:`~wetclutch.rig.experiments`); :mod:`~wetclutch.rig.sensors` is the
sensor chain, :mod:`~wetclutch.rig.files` the measurement files,
:mod:`~wetclutch.rig.calibration` the study's figures.
"""

from .experiments import EXPERIMENTS, RigResult, Settings, run

__all__ = ["EXPERIMENTS", "RigResult", "Settings", "run"]
