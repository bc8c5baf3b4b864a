"""Measured cyclic tests in: curve files + a conditions YAML -> one netCDF per test with the
rigs' variable names (importer.py); the door every measured curve comes through."""
from .curves import read_curve
from .importer import import_test, load_conditions, measured_dataset

__all__ = ["read_curve", "import_test", "load_conditions", "measured_dataset"]
