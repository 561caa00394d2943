"""Everything that is written for people to look at: one writer per product, and the plots.

:mod:`~wetclutch.report.scenario`, :mod:`~wetclutch.report.rig`,
:mod:`~wetclutch.report.calibration`, :mod:`~wetclutch.report.identify`,
:mod:`~wetclutch.report.launch`, :mod:`~wetclutch.report.verify` and
:mod:`~wetclutch.report.main` (the main job); :mod:`~wetclutch.report.plots`.
"""
