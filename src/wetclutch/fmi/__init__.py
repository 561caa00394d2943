"""The clutch model and the launch controller as FMI 2.0 co-simulation FMUs.

:mod:`~wetclutch.fmi.plant` and :mod:`~wetclutch.fmi.controller` are the stepped models;
:mod:`~wetclutch.fmi.plant_fmu` and :mod:`~wetclutch.fmi.controller_fmu` wrap them as
``pythonfmu`` slaves; :mod:`~wetclutch.fmi.export` builds the ``.fmu`` files.
"""
