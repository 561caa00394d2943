"""Identification: from measurement files back to the clutch's parameters, with validation.

``wetclutch.ident.identify([wetclutch.ident.load(f) for f in files])``: the files are read
and checked by :mod:`~wetclutch.ident.recordings`; each estimator is a module of its own
(:mod:`~wetclutch.ident.onset`, :mod:`~wetclutch.ident.friction`,
:mod:`~wetclutch.ident.static`, :mod:`~wetclutch.ident.dynamics`,
:mod:`~wetclutch.ident.ringing`, :mod:`~wetclutch.ident.inertia`, :mod:`~wetclutch.ident.drag`,
:mod:`~wetclutch.ident.supply`); :mod:`~wetclutch.ident.validation` predicts each file
from the others; :mod:`~wetclutch.ident.result` holds the outcome.
"""

from .pipeline import identify
from .recordings import Recording, load, read_channel_map
from .result import Identification

__all__ = ["Identification", "Recording", "identify", "load", "read_channel_map"]
