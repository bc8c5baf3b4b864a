"""The GPU batch's kernels run here under numba's CUDA simulator (CI has no GPU): it must
be switched on before numba.cuda is first imported, which only these tests do."""
import os

import numba
import pytest

os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
numba.config.reload_config()

from .beds import bed  # noqa: E402 (after the simulator is on)


@pytest.fixture(scope="module")
def beds():
    """Three settled beds, the last with its right wall moving inwards."""
    return [bed(40, 1), bed(55, 2), bed(70, 3, wall_speed=0.05)]
