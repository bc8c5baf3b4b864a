"""numba options shared by the kernels.

FAST: fastmath without nnan/ninf/reassoc: same binary -> same bits (run-to-run and across
a checkpoint restart), NaN still propagates to the guards.
NO_NRT: the per-step kernels allocate nothing, so they run without numba's reference
counting (``_nrt=False``; an allocation added later fails to compile instead of running
slowly). With it, arrays handed to inlined helpers (the contact sub-models) cost an atomic
incref/decref pair per contact: measured 2.2x slower on settle2d.
"""
FAST = {"arcp", "contract", "nsz", "afn"}
NO_NRT = dict(cache=True, error_model="numpy", _nrt=False)
LOOP = dict(NO_NRT, fastmath=FAST)
