"""Planted inputs of the calibration tests: a small biaxial specimen, a config whose biaxial
loading consolidates in short windows, and a measured test's conditions YAML (no curve
needed to run a case)."""
from pathlib import Path

import pytest
import yaml

from ballaststudy.rig.biaxial import BiaxialParams, assemble_biaxial
from ballaststudy.rig.library import load_library

from ballaststudy.cluster.pool import LocalPool

from ..biaxial_fast import FAST_LOADING
from ..shipped import ROOT, shipped_config
from .rounds import round_of_two


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


@pytest.fixture(scope="session")
def specimen(small_library, tmp_path_factory):
    """A 0.15 x 0.30 m biaxial specimen of the tiny library (~40 s to assemble)."""
    p = BiaxialParams(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
                      fill_area_ratio=0.9)
    path = tmp_path_factory.mktemp("cal") / "assembled.nc"
    assemble_biaxial(load_library(small_library), p, seed=7).save(path)
    return path


@pytest.fixture(scope="session")
def local_round(specimen, tmp_path_factory, planted_conditions):
    """(config, conditions, curves, case files) of rounds.round_of_two on the local pool
    (2 processes): what every executor must give."""
    folder = tmp_path_factory.mktemp("executor")
    config = shipped_config(folder / "config.yaml", lambda cfg: cfg["rig"]["biaxial"]["loading"].update(
        FAST_LOADING, checkpoint_every=1))
    conditions = _planted_conditions(folder / "t.yaml", 60.0)
    at, files = round_of_two(specimen, config, conditions, folder / "local", LocalPool(2))
    return config, conditions, at, files


@pytest.fixture
def measured_target(tmp_path):
    """(conditions YAML, imported netCDF) of the shipped target sun_et_al_16/p60_q230_f5,
    imported from the shared measured data (skipped where they are not)."""
    from ballaststudy.measured.importer import measured_dataset, write_test
    test = ROOT / "config" / "measured" / "sun_et_al_16" / "p60_q230_f5.yaml"
    data_dir = ROOT / "../shared/data/measured"
    if not data_dir.is_dir():
        pytest.skip("the shared measured data are not here")
    measured = tmp_path / "m.nc"
    write_test(measured_dataset(test, data_dir), measured)
    return test, measured
