"""The fused stepping kernel: K steps of velocity Verlet inside numba, no Python per step.

One step: walls move, half kick + drift (balls, clumps) + force reset -> Verlet rebuild
if two balls (or a ball and a wall) may have closed the skin since the last build (exact
test, see integrate.first_half) -> ball-ball
contacts -> flat joints -> ball-wall contacts -> clump sums -> local damping + half kick
-> guards. Returns early with a status code when a guard trips (after the full step).
"""
import numpy as np
from numba import njit

from . import params as P
from .bonds import bond_forces
from .clumps import gather_clumps, place_pebbles
from .contacts import pack_kinematics, pair_forces
from .integrate import critical_dt, first_half, pebbles_moved, second_half
from .neighbours import grow_rows, rebuild
from .walls import move_walls, wall_forces


@njit(cache=True, error_model="numpy")
def run_steps(nsteps, prm, cnt, err, eacc, lc,
              pos, vel, omega, rad, mass, inertia, minv, iinv, force, moment,
              stone, mat, fix, clump, offset, alive, pos0, clear, fext, damp,
              seg, wvel, womega, centre, wforce, wmoment, wmat, link,
              cpos, cvel, comega, ctheta, cmass, cinertia, cheld, cforce, cmoment, cdamp,
              p_i, p_j, p_h, p_bond, p_fn, p_fs, p_n,
              w_i, w_s, w_h, w_fn, w_fs, w_n,
              b_i, b_j, b_active, rbar, d0, gi, bkn, bks, sigc, coh, tanphi, bmu,
              theta, bmom, state, bfn, bfs,
              l_step, l_time, l_bond, l_elem, l_i, l_j, l_stone, l_mode, l_x, l_y,
              l_stress, l_n):
    """Advance up to ``nsteps`` steps. cnt = [step, neighbour builds, force rebuild flag];
    prm[P.TIME] is advanced. Lists that needed more room are reallocated here, so the
    pair and wall-pair arrays are returned: (status, steps done, p_i, p_j, p_h, p_bond,
    p_fn, p_fs, w_i, w_s, w_h, w_fn, w_fs)."""
    skin = prm[P.SKIN]
    # packed per-ball rows the kernels work on during the chunk (one cache line per ball):
    # kin = (x, y, vx, vy, omega, R, 1/m, material); written back when the chunk ends
    kin = np.empty((pos.shape[0], 8))
    pack_kinematics(pos, vel, omega, rad, minv, mat, kin)
    # one accumulator row (fx, fy, mz) per ball: a single cache line per scattered update;
    # the public force/moment arrays are written back when the chunk ends
    fa = np.zeros((pos.shape[0], 4))
    for i in range(pos.shape[0]):
        fa[i, 0] = force[i, 0]
        fa[i, 1] = force[i, 1]
        fa[i, 2] = moment[i]
    for k in range(nsteps):
        dt = prm[P.DT]
        dt_next = dt
        prm[P.WALL_TRAVEL] += move_walls(seg, wvel, womega, centre, dt)   # wall travel since build
        cx = prm[P.SHIFT_X]
        cy = prm[P.SHIFT_Y]
        wt = prm[P.WALL_TRAVEL]
        d1, d2, near_wall, sx, sy, nfree = first_half(
            dt, prm[P.GX], prm[P.GY], cx, cy, wt, kin, fa, mass, fext, minv, iinv, fix, clump,
            alive, pos0, clear, cpos, cvel, comega, ctheta, cforce, cmoment, cmass, cinertia,
            cheld)
        if cpos.shape[0] > 0:
            place_pebbles(kin, clump, offset, alive, cpos, cvel, comega, ctheta)
            d1, d2, near_wall = pebbles_moved(cx, cy, wt, kin, fa, fext, clump, alive, pos0,
                                              clear, d1, d2, near_wall)
        if nfree > 0:       # next step's common shift: this step's mean displacement
            prm[P.SHIFT_X] = sx / nfree
            prm[P.SHIFT_Y] = sy / nfree
        if cnt[2] > 0 or near_wall or d1 ** 0.5 + d2 ** 0.5 > skin:
            for i in range(pos.shape[0]):
                pos[i, 0] = kin[i, 0]
                pos[i, 1] = kin[i, 1]
            while True:
                st, need = rebuild(pos, rad, alive, clump, pos0, clear, prm[P.SKIN], prm[P.XMIN],
                                   prm[P.YMIN], prm[P.XMAX], prm[P.YMAX], p_i, p_j, p_h,
                                   p_bond, p_n, b_i, b_j, seg, w_i, w_s, w_h, w_n)
                if st == 0:
                    break
                cap = need + need // 4 + 16       # grow the list in place of the caller's
                if st == 1:
                    p_i = grow_rows(p_i, cap)
                    p_j = grow_rows(p_j, cap)
                    p_h = grow_rows(p_h, cap)
                    p_bond = grow_rows(p_bond, cap)
                    p_fn = grow_rows(p_fn, cap)
                    p_fs = grow_rows(p_fs, cap)
                else:
                    w_i = grow_rows(w_i, cap)
                    w_s = grow_rows(w_s, cap)
                    w_h = grow_rows(w_h, cap)
                    w_fn = grow_rows(w_fn, cap)
                    w_fs = grow_rows(w_fs, cap)
            cnt[1] += 1
            cnt[2] = 0
            prm[P.WALL_TRAVEL] = 0.0
            prm[P.SHIFT_X] = 0.0
            prm[P.SHIFT_Y] = 0.0
            if prm[P.AUTO_DT] > 0.0 or prm[P.DSCALE] > 0.0:
                dtc = critical_dt(prm, rad, mass, inertia, minv, iinv, mat, clump, alive,
                                  p_i, p_j, p_n[0], w_i, w_s, w_n[0], wmat, b_i, b_j,
                                  b_active, rbar, bkn, bks, lc)
                for i in range(pos.shape[0]):
                    kin[i, 6] = minv[i]           # density scaling may have changed it
                if prm[P.AUTO_DT] > 0.0 and dtc < 1.0e30:
                    dt_next = prm[P.DT_SAFETY] * dtc   # applies from the next step
        cnt[0] += 1
        prm[P.TIME] += dt
        pair_forces(prm, kin, fa, p_i, p_j, p_h, p_bond, p_fn, p_fs, p_n[0],
                    b_active, lc, eacc)
        if b_i.shape[0] > 0:
            bond_forces(prm, cnt[0], kin, rad, stone, fa,
                        b_i, b_j, b_active, rbar, d0, gi, bkn, bks, sigc, coh, tanphi, bmu,
                        theta, bmom, state, bfn, bfs,
                        l_step, l_time, l_bond, l_elem, l_i, l_j, l_stone, l_mode, l_x, l_y,
                        l_stress, l_n, eacc)
        wall_forces(prm, kin, rad, minv, mat, fa,
                    seg, wvel, womega, centre, wmat, link, wforce, wmoment,
                    w_i, w_s, w_h, w_fn, w_fs, w_n[0], lc, eacc)
        if cpos.shape[0] > 0:
            gather_clumps(prm[P.GX], prm[P.GY], kin, fa, clump, alive, cpos, cmass,
                          cforce, cmoment)
        st = second_half(prm, kin, fa, minv, iinv, fix, clump, alive,
                         damp, cvel, comega, cforce, cmoment, cmass, cinertia, cheld, cdamp,
                         eacc, err)
        if cpos.shape[0] > 0:
            place_pebbles(kin, clump, offset, alive, cpos, cvel, comega, ctheta)
        prm[P.DT] = dt_next
        if st != P.OK:
            _write_back(kin, fa, pos, vel, omega, force, moment)
            return (st, k + 1, p_i, p_j, p_h, p_bond, p_fn, p_fs, w_i, w_s, w_h, w_fn, w_fs)
    _write_back(kin, fa, pos, vel, omega, force, moment)
    return (P.OK, nsteps, p_i, p_j, p_h, p_bond, p_fn, p_fs, w_i, w_s, w_h, w_fn, w_fs)


@njit(cache=True, error_model="numpy")
def _write_back(kin, fa, pos, vel, omega, force, moment):
    for i in range(force.shape[0]):
        pos[i, 0] = kin[i, 0]
        pos[i, 1] = kin[i, 1]
        vel[i, 0] = kin[i, 2]
        vel[i, 1] = kin[i, 3]
        omega[i] = kin[i, 4]
        force[i, 0] = fa[i, 0]
        force[i, 1] = fa[i, 1]
        moment[i] = fa[i, 2]
