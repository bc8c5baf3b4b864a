"""Numba 2D DEM engine in PFC2D conventions (see docs/physics-spec.md).

Public API: ``Simulation`` (build, run, measure, checkpoint), parameter dataclasses
``ContactMaterial`` / ``FlatJointMaterial``, ``SimulationError``, ``inertial_number``,
``BREAK_MODES``.
"""
from .materials import DENSITY_HARD, DENSITY_SOFT, ContactMaterial, FlatJointMaterial
from .output import inertial_number
from .simulation import Simulation, SimulationError

BREAK_MODES = ("tension", "shear")

__all__ = ["Simulation", "SimulationError", "ContactMaterial", "FlatJointMaterial",
           "inertial_number", "BREAK_MODES", "DENSITY_HARD", "DENSITY_SOFT"]
