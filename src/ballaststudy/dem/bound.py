"""The kernels that take the contact law, bound to one law.

numba types a closure's constant as a literal, so ``stepper(law)`` etc. compile the
kernels with the packed law as a compile-time constant (each law its own machine code, see
submodels.py) and cost a plain call afterwards. Calling a kernel that asks for
``numba.literally`` straight from Python would re-dispatch through an exception on every
call (~6 ms). The wrappers are tiny and compiled once per process and law; the kernels
behind them come from numba's on-disk cache.
"""
from functools import lru_cache

from numba import njit

from .contacts import pair_elastic_energy
from .engine import run_steps
from .integrate import ball_springs, critical_dt
from .walls import wall_elastic_energy


@lru_cache(maxsize=None)
def stepper(law):
    @njit
    def bound(nsteps, run, balls, walls, clumps, pr, wp, bonds, log, ctl):
        return run_steps(nsteps, law, run, balls, walls, clumps, pr, wp, bonds, log, ctl)
    return bound


@lru_cache(maxsize=None)
def timestep(law):
    @njit
    def bound(run, balls, pr, wp, wmat, bonds):
        return critical_dt(law, run, balls, pr, wp, wmat, bonds)
    return bound


@lru_cache(maxsize=None)
def springs(law):
    @njit
    def bound(run, balls, pr, wp, wmat, bonds):
        return ball_springs(law, run, balls, pr, wp, wmat, bonds)
    return bound


@lru_cache(maxsize=None)
def elastic_energy(law):
    @njit
    def bound(run, balls, kin, pr, b_active, walls, wp):
        return (pair_elastic_energy(law, run, balls, pr, b_active)
                + wall_elastic_energy(law, run, kin, walls, wp))
    return bound
