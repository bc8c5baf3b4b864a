"""A small box-test case shared by the rig tests: coarse balls (8 mm), a synthetic BPM
library in the bpm package's format, shortened assembly stages, thesis loads."""
import pytest

from ballaststudy.rig.library import synthetic_library
from ballaststudy.rig.params import RigParams

SMALL = dict(drop_max_steps=200000, tamping_steps=8000, relax_steps=2000,
             static_window_steps=1000, static_max_windows=200, servo_velocity_m_s=0.1,
             checkpoint_every=1, snapshot_every=1, fill_area_ratio=0.7)


@pytest.fixture(scope="session")
def small_library(tmp_path_factory):
    path = tmp_path_factory.mktemp("bpm") / "BPM.nc"
    synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(path)
    return path


@pytest.fixture(scope="session")
def small_params():
    return RigParams(**SMALL)


@pytest.fixture(scope="session")
def assembled(tmp_path_factory, small_library, small_params):
    """(path of the assembled case, the BoxRig) built once per session."""
    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.library import load_library
    rig = assemble(load_library(small_library), small_params, seed=7)
    path = tmp_path_factory.mktemp("case") / "assembled.nc"
    rig.save(path)
    return path, rig
