"""The kernels that take the contact law, bound to one law.

numba types a closure's constant as a literal, so ``stepper(law)`` etc. compile the
kernels with the packed law as a compile-time constant (each law its own machine code, see
submodels.py) and cost a plain call afterwards. Calling a kernel that asks for
``numba.literally`` straight from Python would re-dispatch through an exception on every
call (~6 ms). The wrappers are tiny, but compiling one links the kernel behind it into its
own module and optimises the whole (3.7 s per process for ``stepper``), so they are cached
on disk too: numba keys a closure's cache entry on its cell contents, here the law.
"""
from functools import lru_cache

from numba import njit

from .contacts import pair_elastic_energy
from .engine import run_steps
from .integrate import ball_springs, clump_springs, critical_dt
from .walls import wall_elastic_energy


@lru_cache(maxsize=None)
def stepper(law):
    @njit(cache=True)
    def bound(nsteps, run, balls, walls, clumps, pr, wp, bonds, log, ctl):
        return run_steps(nsteps, law, run, balls, walls, clumps, pr, wp, bonds, log, ctl)
    return bound


@lru_cache(maxsize=None)
def timestep(law):
    @njit(cache=True)
    def bound(run, balls, clumps, pr, wp, walls, bonds):
        return critical_dt(law, run, balls, clumps, pr, wp, walls, bonds)
    return bound


@lru_cache(maxsize=None)
def springs(law):
    @njit(cache=True)
    def bound(run, balls, pr, wp, wmat, bonds):
        return ball_springs(law, run, balls, pr, wp, wmat, bonds)
    return bound


@lru_cache(maxsize=None)
def elastic_energy(law):
    @njit(cache=True)
    def bound(run, balls, kin, pr, b_active, walls, wp):
        return (pair_elastic_energy(law, run, balls, pr, b_active)
                + wall_elastic_energy(law, run, kin, walls, wp))
    return bound


@lru_cache(maxsize=None)
def clump_stiffness(law):
    @njit(cache=True)
    def bound(run, balls, clumps, pr, wp, walls, bonds):
        return clump_springs(law, run, balls, clumps, pr, wp, walls, bonds)
    return bound
