"""A small box-test case shared by the rig tests: coarse balls (8 mm), a synthetic BPM
library in the bpm package's format (tests/conftest.py: small_library), shortened
assembly stages, thesis loads."""
import pytest

from ballaststudy.rig.params import RigParams

SMALL = dict(drop_max_steps=200000, tamping_steps=8000, relax_steps=2000,
             static_window_steps=1000, static_max_windows=200, servo_velocity_m_s=0.1,
             checkpoint_every=1, snapshot_every=1, fill_area_ratio=0.7)


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
