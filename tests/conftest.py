"""Shared fixtures: database definitions like config/databases.yaml and one small generated
form database reused by several test files (generated once per session).

The GPU batch (dem/gpu) runs here under numba's CUDA simulator (CI has no GPU): it is
switched on before anything imports numba.cuda, which the package does wherever the
scenario runner is imported (its cuda backend), so here, before any test module. On a
machine with a GPU, BALLASTSTUDY_TEST_GPU=real runs the same tests on it instead.

xdist runs one worker per core, so BLAS and OpenMP threads within a worker only contend
for the cores: they are one per worker (set before numpy loads, inherited by the workers
and by the programs tests start). With OpenBLAS's default two per worker, the loop's
Gaussian-process fits ran 4-5 x slower while the other core was busy (17.6 and 15.8 s
against 3.7 and 3.1 s: docs/how-to/cluster.md, "Threads")."""
import copy
import os

for _threads in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_threads, "1")

import numba  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

if os.environ.get("BALLASTSTUDY_TEST_GPU") != "real":
    os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
    numba.config.reload_config()

from ballaststudy.measured.fetch import fetch  # noqa: E402

from .measured.served import LOCAL_COPY, served  # noqa: E402

MATERIALS = {"hard": {"mass_fraction": 0.7, "density_kg_m3": 2850.0},
             "soft": {"mass_fraction": 0.3, "density_kg_m3": 2620.0}}


@pytest.fixture
def make_definition():
    """Factory for a database definition; keyword arguments override the defaults."""
    def make(**overrides):
        d = {"mass_kg": 10.0, "grading": "G_CRB B", "shape_index": 30.0,
             "particle_length_index": 1.0, "flakiness_index": None,
             "materials": copy.deepcopy(MATERIALS)}
        d.update(overrides)
        return d
    return make


# A coarse grading at 25 kg: the long-stone objective (1 % = 0.25 kg) is several of the
# smallest stones that can be long, so the tolerances are attainable. At 10 kg
# the LI objective (0.1 kg) is about one stone of the 63/80 group and 0.5 pp is below the
# granularity of the aggregate.
SMALL_DB = {"mass_kg": 25.0, "grading": "G_CRB B", "shape_index": 30.0,
            "particle_length_index": 1.0, "flakiness_index": None, "materials": MATERIALS}
SMALL_DB_SEED = 11


@pytest.fixture(scope="session")
def small_database(tmp_path_factory):
    """(path, loaded Dataset, definition) of one small generated database."""
    from ballaststudy.forms.objective import FormParams
    from ballaststudy.forms.pipeline import generate_database

    out = tmp_path_factory.mktemp("small_db")
    definition = copy.deepcopy(SMALL_DB)
    nc = generate_database("small", definition, SMALL_DB_SEED, FormParams(), out)
    with xr.open_dataset(nc) as ds:
        ds = ds.load()
    return nc, ds, definition


@pytest.fixture(scope="session")
def small_library(tmp_path_factory):
    """A synthetic BPM library of 24 coarse stones (8 mm balls) in the bpm package's format:
    the rig and calibration tests' specimens."""
    from ballaststudy.rig.library import synthetic_library
    path = tmp_path_factory.mktemp("bpm") / "BPM.nc"
    synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(path)
    return path


@pytest.fixture(scope="session")
def measured_data_dir(tmp_path_factory):
    """A measured.data_dir filled by `fetch`, the code path a user's `measured fetch` takes,
    from the local copy of the source served over HTTP (skipped where there is none)."""
    if not LOCAL_COPY.is_dir():
        pytest.skip(f"no local copy of the measured curves' source at {LOCAL_COPY}")
    data_dir = tmp_path_factory.mktemp("measured")
    with served(LOCAL_COPY) as url:
        fetch(data_dir, url)
    return data_dir
