"""The simulation core: rotational networks and the compiled hybrid integrator.

* :mod:`~wetclutch.sim.network`: bodies, clutches, brakes, gears, springs and sources as
  Python objects; :func:`~wetclutch.sim.network.integrate`;
* :mod:`~wetclutch.sim.signals`: time signals compiled for the core;
* the core, compiled with numba, one concept a module: :mod:`~wetclutch.sim.workspace`
  (records and their layouts), :mod:`~wetclutch.sim.rhs` (right-hand side and event
  functions), :mod:`~wetclutch.sim.modes` (stick/slip decisions),
  :mod:`~wetclutch.sim.dopri` (the Runge-Kutta pair), :mod:`~wetclutch.sim.linalg`,
  :mod:`~wetclutch.sim.integrator` (:func:`~wetclutch.sim.integrator.advance`), and
  :mod:`~wetclutch.sim.coldstart` (a first run's compilation on two processes).
"""

from .network import GROUND, Network, Trajectory, integrate

__all__ = ["GROUND", "Network", "Trajectory", "integrate"]
