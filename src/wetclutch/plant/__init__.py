"""The study's rig as networks: the driveline, the whole clutch with its actuator, and named scenarios."""

from .scenarios import SCENARIOS, Result, simulate

__all__ = ["SCENARIOS", "Result", "simulate"]
