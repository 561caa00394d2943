"""Physical laws of the clutch and its oil: the lowest layer, plain functions and compiled kernels.

* :mod:`~wetclutch.physics.oil`: ATF viscosity, density and bulk modulus with entrained air;
* :mod:`~wetclutch.physics.friction`: the plate friction law (normal force, knee, inverse);
* :mod:`~wetclutch.physics.actuator`: valve electronics, coil, magnet, valve flows, piston;
  the flat actuator record and its compiled kernel.
"""
