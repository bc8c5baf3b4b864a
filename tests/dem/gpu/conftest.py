"""The GPU batch's tests: its kernels under numba's CUDA simulator (switched on by
tests/conftest.py), on settled beds of disks (beds.py)."""
import pytest

from .beds import bed


@pytest.fixture(scope="module")
def beds():
    """Three settled beds, the last with its right wall moving inwards."""
    return [bed(40, 1), bed(55, 2), bed(70, 3, wall_speed=0.05)]
