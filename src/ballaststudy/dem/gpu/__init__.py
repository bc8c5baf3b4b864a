"""Batched GPU backend of the 2D DEM engine (optional: ``pip install -e '.[cuda]'``).

B independent cases stepped together on one GPU by numba-cuda kernels that call the CPU
engine's contact sub-models; under ``NUMBA_ENABLE_CUDASIM=1`` the same kernels run on the
CPU (numba's CUDA simulator), which is how the tests check them without a GPU.
"""
from .batch import Batch, BatchError, cuda_available

__all__ = ["Batch", "BatchError", "cuda_available"]
