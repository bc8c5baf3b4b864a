"""Planted inputs of the calibration tests: a config whose biaxial loading consolidates in
short windows, and a measured test's conditions YAML (no curve needed to run a case)."""
from pathlib import Path

import pytest
import yaml

from ..biaxial_fast import FAST_LOADING
from ..shipped import shipped_config


def _fast_config(folder):
    """The shipped config with absolute paths and 1000-step consolidation windows."""
    return shipped_config(Path(folder) / "config.yaml",
                          lambda cfg: cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING))


def _planted_conditions(path, q_max_kPa, p_kPa=30.0, q_min_kPa=10.0, **extra):
    """A triaxial test's conditions YAML at p and q bounds (kPa)."""
    path = Path(path)
    path.write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=p_kPa, deviator_min_kPa=q_min_kPa,
        deviator_max_kPa=q_max_kPa, curves=[dict(file="a.dat", quantity="axial_strain", units="1",
                                                   sign="compression_positive")], **extra)))
    return path


@pytest.fixture(scope="session")
def fast_config():
    return _fast_config


@pytest.fixture(scope="session")
def planted_conditions():
    return _planted_conditions
