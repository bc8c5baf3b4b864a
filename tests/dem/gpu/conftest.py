"""The GPU batch's kernels run here under numba's CUDA simulator (CI has no GPU): it must
be switched on before numba.cuda is first imported, which only these tests do."""
import os

import numba

os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
numba.config.reload_config()
