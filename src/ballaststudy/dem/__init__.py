"""Numba 2D DEM engine in PFC2D conventions (verification cases: tests/dem, one per case of
the project physics specification).

Public API: ``Simulation`` (build, run, measure, checkpoint), ``Control`` (controllers
run inside the stepping loop), ``ContactLaw`` (sub-model composition), parameter dataclasses ``ContactMaterial`` / ``FlatJointMaterial``,
``SimulationError``, ``inertial_number``, ``BREAK_MODES``.
"""
from . import _cache

_cache.refresh()    # before any kernel is loaded from the numba cache

from .control import Control  # noqa: E402
from .law import ContactLaw  # noqa: E402
from .materials import DENSITY_HARD, DENSITY_SOFT, ContactMaterial, FlatJointMaterial  # noqa: E402
from .output import inertial_number  # noqa: E402
from .simulation import Simulation, SimulationError  # noqa: E402

BREAK_MODES = ("tension", "shear")

__all__ = ["Simulation", "SimulationError", "Control", "ContactLaw", "ContactMaterial", "FlatJointMaterial",
           "inertial_number", "BREAK_MODES", "DENSITY_HARD", "DENSITY_SOFT"]
