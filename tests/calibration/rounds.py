"""A calibration round of two cases (two values of mu on one specimen, checkpoints every
cycle) to run on each executor, and how their outputs are compared: every variable and
attribute of every case file, bit for bit."""
import time

import numpy as np
import xarray as xr

from ballaststudy.calibration.evaluate import Evaluator

CYCLES = 40            # ~4 s a case: long enough to be killed between its checkpoints
THETAS = np.array([[0.5], [0.7]])


def round_of_two(specimen, config, conditions, out, pool):
    """One round of two parameter sets (mu) on one specimen: their curves and case files."""
    ev = Evaluator(["mu"], [specimen], [(conditions, np.array([1.0, 10.0]))], config, CYCLES,
                   "axial_strain", out, pool=pool)
    return ev(THETAS), sorted((out / "cases").rglob("case*.nc"))


def same_cases(a_files, b_files):
    assert [f.relative_to(f.parents[2]) for f in a_files] == [f.relative_to(f.parents[2]) for f in b_files]
    for a, b in zip(a_files, b_files):
        with xr.open_dataset(a) as A, xr.open_dataset(b) as B:
            assert set(A.variables) == set(B.variables) and A.attrs == B.attrs
            for name in A.variables:
                assert np.array_equal(A[name].values, B[name].values,
                                      equal_nan=A[name].dtype.kind == "f"), (a, name)


def checkpointed_case(cases, timeout_s=120):
    """The first checkpoint a case writes under the folder ``cases``."""
    end = time.time() + timeout_s
    while time.time() < end:
        for checkpoint in cases.rglob("*.checkpoint.npz"):
            return checkpoint
        time.sleep(0.05)
    raise AssertionError(f"no case under {cases} wrote a checkpoint within {timeout_s} s")
