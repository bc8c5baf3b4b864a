"""The stepping kernel: K steps of velocity Verlet inside numba, no Python per step.

One step: walls move, half kick + drift (balls, clumps) + force reset -> Verlet rebuild
if two balls (or a ball and a wall) may have closed the skin since the last build (exact
test, see integrate.first_half) -> ball-ball contacts -> flat joints -> ball-wall
contacts -> local damping + half kick -> clumps -> guards -> rigid stones that reached
their strength (crushing.py, every CRUSH_EVERY steps) -> controllers (control.py, every
``every`` steps). Returns early with a status code when a guard trips or a
controller raises an event (after the full step). (A fused pass — each ball integrated right
after its row of the half list — was tried and measured slower: +30 % per ball.)

State comes as named containers (state.py): ``run`` (RunState: parameters, counters,
energy accumulators, the contact law and its table), balls, walls, clumps, the two
Verlet lists, bonds, the breakage log and the controllers (``ctl``, control.py; ``every``
= 0: none).
"""
import numba
import numpy as np
from numba import njit

from . import params as P
from .bonds import bond_forces, bond_scratch
from .clumps import gather_clumps, place_pebbles
from .contacts import pack_kinematics, pair_forces
from .control import EVERY, PENDING, actuate, control_step
from .crushing import overloaded
from .integrate import clumps_damp_kick, critical_dt, first_half, guards, second_half
from .neighbours import grow_rows, rebuild
from .state import PairsArrays, WallPairsArrays
from .walls import move_walls, wall_forces


@njit(cache=True, error_model="numpy")
def _grown_pairs(pr, cap):
    return PairsArrays(grow_rows(pr.i, cap), grow_rows(pr.j, cap), grow_rows(pr.hist, cap),
                       grow_rows(pr.bond, cap), grow_rows(pr.fn, cap), grow_rows(pr.fs, cap),
                       grow_rows(pr.lap0, cap), pr.n)


@njit(cache=True, error_model="numpy")
def _grown_wall_pairs(wp, cap):
    return WallPairsArrays(grow_rows(wp.i, cap), grow_rows(wp.s, cap), grow_rows(wp.hist, cap),
                           grow_rows(wp.fn, cap), grow_rows(wp.fs, cap), wp.n)


@njit(cache=True, error_model="numpy")
def rebuild_lists(run, balls, walls, pr, wp, bonds):
    """Rebuild both Verlet lists (growing them as needed) and reset the rebuild
    bookkeeping. Returns the (possibly new) list containers."""
    prm = run.prm
    while True:
        st, need = rebuild(prm, balls, pr, wp, bonds, walls.seg)
        if st == 0:
            break
        cap = need + need // 4 + 16
        if st == 1:
            pr = _grown_pairs(pr, cap)
        else:
            wp = _grown_wall_pairs(wp, cap)
    run.cnt[1] += 1
    run.cnt[2] = 0
    prm[P.WALL_TRAVEL] = 0.0
    prm[P.SHIFT_X] = 0.0
    prm[P.SHIFT_Y] = 0.0
    return pr, wp


@njit(cache=True, error_model="numpy")
def run_steps(nsteps, law, run, balls, walls, clumps, pr, wp, bonds, log, ctl):
    """Advance up to ``nsteps`` steps with the contact law ``law`` (packed, compiled as a
    constant: submodels.py). run.cnt = [step, neighbour builds, force rebuild flag];
    prm[P.TIME] is advanced. Lists that needed more room are reallocated here, so they are
    returned: (status, steps done, pairs, wall pairs)."""
    numba.literally(law)
    prm = run.prm
    cnt = run.cnt
    n = balls.pos.shape[0]
    # packed per-ball rows the kernels work on during the chunk (one cache line per ball):
    # kin = (x, y, vx, vy, omega, R, 1/m, material); written back when the chunk ends
    kin = np.empty((n, 8))
    pack_kinematics(balls, kin)
    # one accumulator row (fx, fy, mz) per ball: a single cache line per scattered update;
    # the public force/moment arrays are written back when the chunk ends
    # (a dead ball of no clump gets 0, and nothing adds to its row after)
    fa = np.zeros((n, 4))
    for i in range(n):
        if balls.alive[i] or balls.clump[i] >= 0:
            fa[i, 0] = balls.force[i, 0]
            fa[i, 1] = balls.force[i, 1]
            fa[i, 2] = balls.moment[i]
    bond_work = bond_scratch(bonds.i.shape[0])
    # joints only break within a chunk: none active now (rigid stones keep theirs as a
    # record, inactive), none all chunk
    jointed = False
    for b in range(bonds.active.shape[0]):
        if bonds.active[b]:
            jointed = True
            break
    has_clumps = clumps.pos.shape[0] > 0
    # a clump's balls, ascending: all of them, and those outside bodies can reach (the
    # buried ones are placed only where the chunk may end or a guard looks)
    live = balls.alive != 0
    every_pebble = np.nonzero((balls.clump >= 0) & live)[0]
    pebbles = every_pebble
    if (balls.buried != 0).any():
        pebbles = np.nonzero((balls.clump >= 0) & live & (balls.buried == 0))[0]
    # the live balls of no clump: the only ones the halves of the step integrate (an
    # assembly's cut leaves dead slots, a rigid specimen has none free)
    free = np.nonzero((balls.clump < 0) & live)[0]
    dense = 2 * free.shape[0] > n
    controlled = ctl.cfg[EVERY] > 0
    crush_every = int(prm[P.CRUSH_EVERY]) if has_clumps else 0
    if controlled and ctl.cfg[PENDING] > 0:     # velocities an event left pending
        actuate(clumps, walls, ctl)
    for k in range(nsteps):
        dt = prm[P.DT]
        dt_next = dt
        prm[P.WALL_TRAVEL] += move_walls(walls.seg, walls.vel, walls.omega, walls.centre, dt)
        d1, d2, near_wall, sx, sy, nfree = first_half(prm, kin, fa, balls, clumps, free, dense)
        pebbles_astray = False
        if has_clumps:
            pebbles_astray, d1, d2, near_wall = place_pebbles(
                prm, kin, fa, balls, clumps, pebbles, True, d1, d2, near_wall)
        if nfree > 0:       # next step's common shift: this step's mean displacement
            prm[P.SHIFT_X] = sx / nfree
            prm[P.SHIFT_Y] = sy / nfree
        if cnt[2] > 0 or near_wall or d1 ** 0.5 + d2 ** 0.5 > prm[P.SKIN]:
            for i in range(n):
                balls.pos[i, 0] = kin[i, 0]
                balls.pos[i, 1] = kin[i, 1]
            pr, wp = rebuild_lists(run, balls, walls, pr, wp, bonds)
            if prm[P.AUTO_DT] > 0.0 or prm[P.DSCALE] > 0.0:
                dtc = critical_dt(law, run, balls, clumps, pr, wp, walls, bonds)
                for i in range(n):
                    kin[i, 6] = balls.minv[i]     # density scaling may have changed it
                if prm[P.AUTO_DT] > 0.0 and dtc < 1.0e30:
                    dt_next = prm[P.DT_SAFETY] * dtc   # applies from the next step
        cnt[0] += 1
        prm[P.TIME] += dt
        pair_forces(law, run, kin, fa, pr, bonds.active)
        if jointed:
            bond_forces(run, kin, balls, fa, bonds, log, bond_work)
        wall_forces(law, run, kin, fa, walls, wp)
        suspect = second_half(prm, kin, fa, balls, run.eacc, free, dense)
        if has_clumps:
            gather_clumps(prm[P.GX], prm[P.GY], kin, fa, balls, clumps, pebbles)
            run.eacc[P.E_LOCAL] += clumps_damp_kick(clumps, 0.5 * dt, dt)
            # the pebbles' full-step motion only where the chunk ends after this step or a
            # guard looks: nothing else reads it (the stress check reads the positions, the
            # controllers clumps and walls; the next step places them again)
            if pebbles_astray or suspect or k == nsteps - 1:
                suspect |= _placed(prm, kin, fa, balls, clumps, every_pebble)
        st = guards(prm, kin, balls.alive, run.err) if suspect else P.OK
        prm[P.DT] = dt_next
        # a controller's event at the same step wins the status; Simulation._run_kernel
        # then makes the split too
        if st == P.OK and crush_every > 0 and cnt[0] % crush_every == 0 \
                and overloaded(prm, kin, balls, clumps, pr, wp, walls.seg):
            st = P.STONES_OVERLOADED
        if st in (P.OK, P.STONES_OVERLOADED) and controlled \
                and control_step(prm, cnt[0], clumps, walls, ctl):
            st = P.CONTROL_EVENT
        if st != P.OK:
            if has_clumps and not (pebbles_astray or suspect or k == nsteps - 1) \
                    and _placed(prm, kin, fa, balls, clumps, every_pebble):
                g = guards(prm, kin, balls.alive, run.err)    # a guard wins, as at any step
                st = g if g != P.OK else st
            _write_back(kin, fa, balls)
            return st, k + 1, pr, wp
    _write_back(kin, fa, balls)
    return P.OK, nsteps, pr, wp


@njit(cache=True, error_model="numpy", inline="always")
def _placed(prm, kin, fa, balls, clumps, pebbles):
    """place_pebbles without the list check: whether a pebble may have tripped a guard."""
    return place_pebbles(prm, kin, fa, balls, clumps, pebbles, False, 0.0, 0.0, False)[0]


@njit(cache=True, error_model="numpy")
def _write_back(kin, fa, balls):
    for i in range(fa.shape[0]):
        balls.pos[i, 0] = kin[i, 0]
        balls.pos[i, 1] = kin[i, 1]
        balls.vel[i, 0] = kin[i, 2]
        balls.vel[i, 1] = kin[i, 3]
        balls.omega[i] = kin[i, 4]
        balls.force[i, 0] = fa[i, 0]
        balls.force[i, 1] = fa[i, 1]
        balls.moment[i] = fa[i, 2]
