"""CUDA kernels of the batched engine: one thread per ball (or per case, per segment) of
all cases at once, compiled per contact law (the packed law is a constant of the closure,
as ``numba.literally`` makes it one on the CPU).

The ball-ball force is computed by the contact law of the CPU engine
(``submodels.contact_force``, called as a device function) from a FULL neighbour list:
each ball's thread evaluates each of its contacts itself, with the bodies in the CPU's
order (lower index = body i), and keeps its own copy of the contact's history. Both
copies see the same inputs and evolve bit for bit alike, so action equals reaction
exactly and no thread writes another ball's force (no atomics, no ordering between
threads). It costs each contact twice; a half list would need atomics on both balls.

Flat joints the same way (``flat_joint``): the thread of each of its two balls evaluates
the joint on that side's copy of its state; side 0 writes the breakage log.

Lists are slot-major (``nb[k, i]``, history row k N + i): the threads of a warp read
adjacent rows.

One step, in launch order (each a kernel over the index named); launches are few because
each costs microseconds of the host even when prepared (batch._Prepared):
  walls_step (segment; case): reset the reaction, move the segment, add its travel to the
      case's; clear the case's rebuild flag, count its step
  first_half (ball): half kick (from the full-step velocity), drift; a ball whose
      displacement since the build, doubled, plus the wall travel exceeds the skin flags
      its case (the CPU rebuilds on its own exact criterion: the build times differ, the
      forces do not)
  clumps_first (clump; only if there are clumps): half kick, drift, pebbles placed and
      checked like free balls
  bin, build (ball; flagged cases only): cell list, Verlet rows carrying history
  ball_springs (ball; flagged cases with density scaling or the automatic dt): inertial
      masses raised so that the case's dt is stable over the new rows, the case's dt_crit
      (integrate.critical_dt)
  forces (ball): empty the cells of a rebuilt case, contacts, walls, flat joints, weight
      and load, local damping, half kick, guards (a pebble keeps its raw force)
  clumps_second (clump): pebble forces gathered, damping, half kick, pebble velocities
  cases_step (case): time, the automatic dt for the next step, controllers (case_control:
      the CPU's control_step on the case's rows), budget; an event or a spent budget halts
      the case
Every kernel skips the balls, segments and clumps of a halted case (``halt``), so a case
waits unchanged until its host resumes it (cases_resume first imposes the velocities an
event left pending, as a CPU run does at its start).
(unbin empties the cells after the batch's first build, which precedes the first step.)
"""
import math
from collections import namedtuple

from numba import cuda, njit
from numba.core import config

from .. import params as P
from ..bonds import (MODE_SHEAR, MODE_TENSION, broken_element, joint_frame, strip_energy,
                     strip_integrals)
from ..clumps import pebble_motion
from ..control import EVERY, PENDING, ControlArrays, actuate, control_step
from ..integrate import locally_damped
from ..jit import NO_NRT
from ..neighbours import seg_closest
from ..submodels import NCOEF, WIDTH, contact_force, contact_stiffness, lf
from ..walls import wall_contact_point

# per-case scalar columns (``cfg``) and error bits (``err``); SCALE2: density scaling's
# (dt / safety)^2, 0 when the case runs on its real masses
DT, GX, GY, THICK, SKIN, VMAX2, X0, Y0, X1, Y1, CELL, SCALE2, AUTO, SAFETY = range(14)
NCFG = 14               # AUTO: 1 if the case's dt follows its contacts (the CPU's automatic
NO_DT = 1.0e30          # dt: safety x dt_crit after each rebuild); NO_DT: none found yet
# flat-joint constants (rows of ``bc``) and per-side state columns (``bsc``); the
# breakage log: ``logi`` (step, bond, element, mode), ``logf`` (x, y, stress)
RBAR, D0, GI, KN, KS, SIGC, COH, TANPHI, MU = range(9)
THETA, MOMENT = 0, 1
ERR_NEIGHBOURS, ERR_CELL, ERR_WALLS, ERR_GUARD = 1, 2, 4, 8
# a case's state (``halt``): stepping, halted after its budget of steps, halted by an event
# of its controllers; a halted case's threads return at once until the host resumes it
RUNNING, HALT_STEPS, HALT_EVENT = 0, 1, 2
# the batch's clumps and walls with the fields the controllers read and drive (control.py)
ClumpView = namedtuple("ClumpView", "pos vel omega force mass held")
WallView = namedtuple("WallView", "seg force vel")
# a case's counts in the packed controller arrays (``cdim`` columns)
N_SENSORS, N_MEMBERS, N_ACTUATORS, N_CONTROLLERS, N_SAMPLES = range(5)
ERROR_TEXT = {ERR_NEIGHBOURS: "a ball has more neighbours than the list holds",
              ERR_CELL: "a cell holds more balls than it has room for",
              ERR_WALLS: "a ball is near more wall segments than its list holds",
              ERR_GUARD: "NaN, runaway velocity or a ball left the domain"}


@njit(cache=True, inline="always")
def row(coef, b, ma, mb):
    """Coefficient row of materials (ma, mb) of case b, as submodels.coefficient_row."""
    return (coef[b, ma, mb, 0], coef[b, ma, mb, 1], coef[b, ma, mb, 2],
            coef[b, ma, mb, 3], coef[b, ma, mb, 4], coef[b, ma, mb, 5],
            coef[b, ma, mb, 6], coef[b, ma, mb, 7], coef[b, ma, mb, 8],
            coef[b, ma, mb, 9], coef[b, ma, mb, 10], coef[b, ma, mb, 11])


@njit(cache=True, inline="always")
def cell_of(cfg, grid, b, x, y):
    """Cell (cx, cy) of point (x, y) in case b's grid (clamped to it)."""
    cs = cfg[b, CELL]
    ncx = grid[b, 0]
    ncy = grid[b, 1]
    cx = min(max(int((x - cfg[b, X0]) / cs), 0), ncx - 1)
    cy = min(max(int((y - cfg[b, Y0]) / cs), 0), ncy - 1)
    return cx, cy


@njit(**NO_NRT)
def case_control(b, prm, step, resume, cpos, cvel, comega, cforce, cmass, cheld, seg, wforce,
                 wvel, ccfg, csens, cmemb, cscale, cact, cctl, ccpar, ccst, cval, cwsum, csamp,
                 cdim):
    """Case b's controllers (control.py) on its rows of the packed arrays (ball, segment and
    clump indices there are the batch's): at a resume the velocities an event left
    pending; else the control step after a step (True: an event)."""
    ns = cdim[b, N_SENSORS]
    nk = cdim[b, N_CONTROLLERS]
    c = ControlArrays(ccfg[b], csens[b, :ns], cmemb[b, :cdim[b, N_MEMBERS]], cscale[b, :ns],
                      cact[b, :cdim[b, N_ACTUATORS]], cctl[b, :nk], ccpar[b, :nk],
                      ccst[b, :nk], cval[b, :ns], cwsum[b, :ns],
                      csamp[b, :cdim[b, N_SAMPLES], :ns + 1])
    clumps = ClumpView(cpos, cvel, comega, cforce, cmass, cheld)
    walls = WallView(seg, wforce, wvel)
    if resume:
        if c.cfg[PENDING] > 0:
            actuate(clumps, walls, c)
        return False
    return control_step(prm[b], step, clumps, walls, c)


if config.ENABLE_CUDASIM:
    # numba's CUDA simulator runs the kernels as Python and hands them wrapped arrays,
    # which compiled functions cannot take: give those the numpy arrays they wrap
    from numba.cuda.simulator.cudadrv.devicearray import FakeWithinKernelCUDAArray

    def _unwrapped(f):
        def call(*args):
            return f(*(a._item._ary if isinstance(a, FakeWithinKernelCUDAArray) else a
                       for a in args))
        return call

    contact_force = _unwrapped(contact_force)
    wall_contact_point = _unwrapped(wall_contact_point)
    row = _unwrapped(row)
    cell_of = _unwrapped(cell_of)
    case_control = _unwrapped(case_control)

_compiled = {}


def kernels(law, forces_registers=None):
    """The kernels for the packed contact law ``law`` (compiled once per law).
    ``forces_registers``: a cap on the registers of a ``forces`` thread (ptxas'
    maxrregcount; uncapped it takes ~168 on sm_90, 3 blocks an SM), for benchmarks that
    weigh occupancy against spills; no effect under the simulator, which has none."""
    key = (law, forces_registers)
    if key not in _compiled:
        _compiled[key] = _make(law, forces_registers)
    return _compiled[key]


def _make(LAW, forces_registers=None):   # noqa: C901 (one closure per law: LAW a constant)
    assert NCOEF == 12
    capped = cuda.jit if not forces_registers or config.ENABLE_CUDASIM else \
        cuda.jit(max_registers=int(forces_registers))
    HW = lf(LAW, WIDTH)       # history columns (reset when a contact opens); the
    #                          persistent state after them is kept, as on the CPU

    @cuda.jit
    def walls_step(seg, wvel, womega, centre, wforce, wmoment, wcase, travel, cfg, moving,
                   need, clock, halt):
        s = cuda.grid(1)
        if s < need.shape[0]:
            need[s] = 0       # this step's first_half flags the cases to rebuild
            if halt[s] == 0:
                clock[s] += 1     # the case's step under way (1 = its first in the batch)
        if s >= seg.shape[0] or halt[wcase[s]] != 0:
            return
        wforce[s, 0] = 0.0
        wforce[s, 1] = 0.0
        wmoment[s] = 0.0
        if moving == 0:
            return
        b = wcase[s]
        dt = cfg[b, DT]
        c = math.cos(womega[s] * dt)
        sn = math.sin(womega[s] * dt)
        dmax = 0.0
        for e in range(2):
            x = seg[s, 2 * e] - centre[s, 0]
            y = seg[s, 2 * e + 1] - centre[s, 1]
            nxp = centre[s, 0] + c * x - sn * y + wvel[s, 0] * dt
            nyp = centre[s, 1] + sn * x + c * y + wvel[s, 1] * dt
            dmax = max(dmax, math.sqrt((nxp - seg[s, 2 * e]) ** 2 + (nyp - seg[s, 2 * e + 1]) ** 2))
            seg[s, 2 * e] = nxp
            seg[s, 2 * e + 1] = nyp
        centre[s, 0] += wvel[s, 0] * dt
        centre[s, 1] += wvel[s, 1] * dt
        cuda.atomic.add(travel, b, dmax)    # summed per segment: an upper bound

    @cuda.jit
    def first_half(pos, vel, omega, vend, wend, force, minv, iinv, fix, alive, case, pos0,
                   cfg, travel, need, relist, clump, halt):
        i = cuda.grid(1)
        if i >= pos.shape[0] or alive[i] == 0 or clump[i] >= 0:
            return            # (a clump's pebbles: clumps_first)
        b = case[i]
        if halt[b] != 0:
            return
        dt = cfg[b, DT]
        h = 0.5 * dt
        f = fix[i]
        vel[i, 0] = vend[i, 0] if f & 1 else vend[i, 0] + h * force[i, 0] * minv[i]
        vel[i, 1] = vend[i, 1] if f & 2 else vend[i, 1] + h * force[i, 1] * minv[i]
        omega[i] = wend[i] if f & 4 else wend[i] + h * force[i, 2] * iinv[i]
        pos[i, 0] += dt * vel[i, 0]
        pos[i, 1] += dt * vel[i, 1]
        dx = pos[i, 0] - pos0[i, 0]
        dy = pos[i, 1] - pos0[i, 1]
        # a plain store of 1 from any ball that moved too far (an atomic max per ball
        # over the case serialised the whole batch on a few addresses)
        if 2.0 * math.sqrt(dx * dx + dy * dy) + travel[b] > cfg[b, SKIN] or relist[b]:
            need[b] = 1

    @cuda.jit(device=True, inline=True)
    def rebuilding(i, alive, case, need):
        """The case of ball i if the ball is alive and its case rebuilds now, else -1."""
        if i >= alive.shape[0] or alive[i] == 0:
            return -1
        b = case[i]
        return b if need[b] != 0 else -1

    @cuda.jit
    def bin_balls(pos, alive, case, cfg, grid, need, cell_n, cell_ids, bcell, err):
        i = cuda.grid(1)
        b = rebuilding(i, alive, case, need)
        if b < 0:
            return
        cx, cy = cell_of(cfg, grid, b, pos[i, 0], pos[i, 1])
        c = grid[b, 2] + cy * grid[b, 0] + cx
        bcell[i] = c
        k = cuda.atomic.add(cell_n, c, 1)
        if k < cell_ids.shape[1]:
            cell_ids[c, k] = i
        else:
            cuda.atomic.or_(err, b, ERR_CELL)

    @cuda.jit(device=True, inline=True)
    def carried(ids, hist, n_old, i, nball, j, hist2, p, width):
        """Row p of hist2 := the history ball i had with j in its old row (ids, hist),
        zero if j was not listed."""
        for c in range(width):
            hist2[p, c] = 0.0
        for k in range(n_old):
            if ids[k, i] == j:
                for c in range(width):
                    hist2[p, c] = hist[k * nball + i, c]
                return

    @cuda.jit(device=True, inline=True)
    def entered(ids, hist, ids2, hist2, n, n_old, i, other, width, err, b, bit):
        """``other`` enters slot n of ball i's new row (ids2, hist2) with the history it
        carries; returns the new count (unchanged if the row is full: error ``bit``)."""
        if n >= ids.shape[0]:
            cuda.atomic.or_(err, b, bit)
            return n
        nball = ids.shape[1]
        ids2[n, i] = other
        carried(ids, hist, n_old, i, nball, other, hist2, n * nball + i, width)
        return n + 1

    @cuda.jit(device=True, inline=True)
    def adopt(ids, hist, ids2, hist2, n, i, nball, width):
        """Ball i's new row (ids2, hist2) becomes its row (ids, hist)."""
        for k in range(n):
            ids[k, i] = ids2[k, i]
            for c in range(width):
                hist[k * nball + i, c] = hist2[k * nball + i, c]

    @cuda.jit(device=True, inline=True)
    def bonded(i, j, bl, bln, bij, bactive):
        """An active flat joint joins i and j (its pair is no contact: CPU pair_forces)."""
        for k in range(bln[i]):
            q = bl[k, i]
            if bij[0, q] + bij[1, q] - i == j:
                return bactive[0 if bij[0, q] == i else 1, q] != 0
        return False

    @cuda.jit
    def build(pos, rad, alive, case, cfg, grid, need, cell_n, cell_ids, nb, nbn, nh, nb2,
              nh2, seg, wlo, whi, wl, wln, wh, wl2, wh2, pos0, travel, bl, bln, bij,
              bactive, relist, clump, err):
        """New rows are written beside the old ones (nb2, nh2; wl2, wh2), searched in
        the old row for the history they carry, then copied over: each thread touches
        its own rows only, in global memory (slot-major: coalesced)."""
        i = cuda.grid(1)
        b = rebuilding(i, alive, case, need)
        if b < 0:
            return
        if i == 0 or case[i - 1] != b:
            travel[b] = 0.0       # read by first_half only, before this kernel
            relist[b] = 0
        nball = nb.shape[1]
        width = nh.shape[1]
        x = pos[i, 0]
        y = pos[i, 1]
        r = rad[i]
        skin = cfg[b, SKIN]
        cx, cy = cell_of(cfg, grid, b, x, y)
        ncx = grid[b, 0]
        ncy = grid[b, 1]
        n_old = nbn[i]
        n = 0
        for ey in range(max(cy - 1, 0), min(cy + 2, ncy)):
            for ex in range(max(cx - 1, 0), min(cx + 2, ncx)):
                c = grid[b, 2] + ey * ncx + ex
                for q in range(min(cell_n[c], cell_ids.shape[1])):
                    j = cell_ids[c, q]
                    if j == i or (clump[i] >= 0 and clump[j] == clump[i]):
                        continue
                    dx = pos[j, 0] - x
                    dy = pos[j, 1] - y
                    lim = r + rad[j] + skin
                    if dx * dx + dy * dy >= lim * lim or bonded(i, j, bl, bln, bij, bactive):
                        continue
                    n = entered(nb, nh, nb2, nh2, n, n_old, i, j, width, err, b, ERR_NEIGHBOURS)
        adopt(nb, nh, nb2, nh2, n, i, nball, width)
        nbn[i] = n
        # the case's wall segments, the same way
        n_old = wln[i]
        n = 0
        for s in range(wlo[b], whi[b]):
            px, py, u = seg_closest(x, y, seg[s, 0], seg[s, 1], seg[s, 2], seg[s, 3])
            lim = r + skin
            if (x - px) ** 2 + (y - py) ** 2 >= lim * lim:
                continue
            n = entered(wl, wh, wl2, wh2, n, n_old, i, s, width, err, b, ERR_WALLS)
        adopt(wl, wh, wl2, wh2, n, i, nball, width)
        wln[i] = n
        pos0[i, 0] = x
        pos0[i, 1] = y

    @cuda.jit(device=True, inline=True)
    def pair_springs(coef, mat, rad, b, i, j, t):
        """A ball-ball contact's springs on ball i: (k_n + k_s, k_s R_i^2 + k_r), the bodies
        in the CPU's order (integrate._add_pair_springs)."""
        lo = min(i, j)
        hi = max(i, j)
        kn, ks, kr = contact_stiffness(LAW, row(coef, b, mat[lo], mat[hi]), rad[lo], rad[hi], t)
        return kn + ks, ks * rad[i] * rad[i] + kr

    @cuda.jit
    def ball_springs(pos0, rad, mass, inertia, minv, iinv, mat, alive, case, cfg, coef, nb,
                     nbn, wl, wln, wmat, bl, bln, bij, bc, bactive, clump, need, dtc):
        """integrate.critical_dt at a rebuild: k_tr and k_rot of the ball over its new rows
        (the full list: its own contacts), its walls and its flat joints (a jointed pair
        within the skin counts its contact springs too, as the list leaves it out); with
        density scaling 1/m = 1/max(m, k_tr s2), 1/I likewise (free balls with springs
        only); with the automatic dt the case's dt_crit, the least over its balls (clumps'
        pebbles too) of sqrt(m/k_tr) and sqrt(I/k_rot), into dtc. Summed in another order
        than the CPU's half list: round-off."""
        i = cuda.grid(1)
        b = rebuilding(i, alive, case, need)
        if b < 0:
            return
        auto = cfg[b, AUTO] > 0.0
        s2 = cfg[b, SCALE2]
        pebble = clump[i] >= 0
        if not auto and (s2 == 0.0 or pebble):
            return
        t = cfg[b, THICK]
        skin = cfg[b, SKIN]
        ri = rad[i]
        ktr = 0.0
        krot = 0.0
        for k in range(nbn[i]):
            k_tr, k_rot = pair_springs(coef, mat, rad, b, i, nb[k, i], t)
            ktr += k_tr
            krot += k_rot
        for k in range(wln[i]):
            s = wl[k, i]
            kn, ks, kr = contact_stiffness(LAW, row(coef, b, wmat[s], mat[i]), 0.0, ri, t)
            ktr += kn + ks
            krot += ks * ri * ri + kr
        for k in range(bln[i]):
            q = bl[k, i]
            side = 0 if bij[0, q] == i else 1
            if bactive[side, q] == 0:
                continue
            j = bij[1 - side, q]
            dx = pos0[j, 0] - pos0[i, 0]
            dy = pos0[j, 1] - pos0[i, 1]
            cut = ri + rad[j] + skin
            if dx * dx + dy * dy < cut * cut:    # (never i's own clump: not jointed)
                k_tr, k_rot = pair_springs(coef, mat, rad, b, i, j, t)
                ktr += k_tr
                krot += k_rot
            a = 2.0 * bc[RBAR, q] * t
            ktr += (bc[KN, q] + bc[KS, q]) * a
            krot += bc[KN, q] * t * (2.0 * bc[RBAR, q]) ** 3 / 12.0 + bc[KS, q] * a * ri * ri
        if ktr == 0.0:
            return
        if s2 > 0.0 and not pebble:
            minv[i] = 1.0 / max(mass[i], ktr * s2)
            iinv[i] = 1.0 / max(inertia[i], krot * s2)
        if auto:
            d = math.sqrt(1.0 / (minv[i] * ktr))
            if krot > 0.0:
                d = min(d, math.sqrt(1.0 / (iinv[i] * krot)))
            cuda.atomic.min(dtc, b, d)

    @cuda.jit
    def unbin(alive, case, need, cell_n, bcell):
        i = cuda.grid(1)
        if i >= alive.shape[0] or alive[i] == 0:
            return
        if need[case[i]] != 0:
            cell_n[bcell[i]] = 0

    @cuda.jit(device=True)
    def flat_joint(q, side, pos, vel, omega, rad, dt, t, bij, bc, bsc, bstate, bfn, bfs,
                   bactive, step, logi, logf, logn, eacc):
        """Flat joint q evaluated by the thread of its ball ``side`` (0: i, 1: j) on that
        side's copy of its state, as bonds.py does it (theta advanced, elements with
        failure, broken elements' response, the interface removed when apart): both
        copies see the same inputs and stay equal; side 0 logs the breakages. Returns
        (removed, fx, fy, moment) on the calling ball."""
        i = bij[0, q]
        j = bij[1, q]
        d, nx, ny, ai, vt = joint_frame(
            pos[i, 0], pos[i, 1], vel[i, 0], vel[i, 1], omega[i], rad[i],
            pos[j, 0], pos[j, 1], vel[j, 0], vel[j, 1], omega[j], rad[j])
        tx = -ny
        ty = nx
        aj = d - ai
        th = bsc[side, q, THETA] + (omega[j] - omega[i]) * dt
        bsc[side, q, THETA] = th
        rbar = bc[RBAR, q]
        ne = bstate.shape[2]
        gc = d - bc[D0, q]
        le = 2.0 * rbar * (1.0 / ne)
        ae = le * t
        knt = bc[KN, q] * t
        ksa = bc[KS, q] * ae
        dfs = ksa * vt * dt
        ftot_n = 0.0
        ftot_s = 0.0
        mc = 0.0
        nbonded = 0
        for e in range(ne):
            a = -rbar + e * le
            fs = bfs[side, q, e] - dfs
            if bstate[side, q, e]:
                i0, i1 = strip_integrals(gc, th, a, a + le, False)
                fn = knt * i0
                if fn >= bc[SIGC, q] * ae or abs(fs) >= bc[COH, q] * ae - fn * bc[TANPHI, q]:
                    tension = fn >= bc[SIGC, q] * ae
                    if side == 0:
                        k = cuda.atomic.add(logn, 0, 1)
                        se = a + 0.5 * le
                        logi[k, 0] = step
                        logi[k, 1] = q
                        logi[k, 2] = e
                        logi[k, 3] = MODE_TENSION if tension else MODE_SHEAR
                        logf[k, 0] = pos[i, 0] + ai * nx - se * ny
                        logf[k, 1] = pos[i, 1] + ai * ny + se * nx
                        logf[k, 2] = (fn if tension else abs(fs)) / ae
                    bstate[side, q, e] = 0
                    e_break = (0.5 * knt * strip_energy(gc, th, a, a + le, False)
                               + 0.5 * fs * fs / ksa)
                    fn, fs, i1 = broken_element(eacc, gc, th, a, le, fs, knt, ksa, bc[MU, q],
                                                 e_break)
                else:
                    nbonded += 1
            else:
                fn, fs, i1 = broken_element(eacc, gc, th, a, le, fs, knt, ksa, bc[MU, q], -1.0)
            bfn[side, q, e] = fn
            bfs[side, q, e] = fs
            ftot_n += fn
            ftot_s += fs
            mc += knt * i1
        if nbonded == 0 and gc - abs(th) * rbar > bc[GI, q]:
            bactive[side, q] = 0      # apart beyond the installation gap: removed
            for e in range(ne):
                bfn[side, q, e] = 0.0
                bfs[side, q, e] = 0.0
            bsc[side, q, MOMENT] = 0.0
            return True, 0.0, 0.0, 0.0
        bsc[side, q, MOMENT] = mc
        fx = -ftot_n * nx + ftot_s * tx          # on j (tension pulls j to i)
        fy = -ftot_n * ny + ftot_s * ty
        if side == 1:
            return False, fx, fy, mc - aj * ftot_s
        return False, -fx, -fy, -mc - ai * ftot_s

    @capped
    def forces(pos, vel, omega, vend, wend, rad, mass, minv, iinv, fix, damp, mat, alive,
               case, fext, force, cfg, coef, nb, nbn, nh, seg, link, wvel, womega, centre, wmat, wl,
               wln, wh, wforce, wmoment, need, cell_n, bcell, bl, bln, bij, bc, bsc,
               bstate, bfn, bfs, bactive, relist, clock, logi, logf, logn, clump, err, halt):
        i = cuda.grid(1)
        if i >= pos.shape[0] or alive[i] == 0:
            return
        b = case[i]
        if halt[b] != 0:
            return
        if need[b] != 0:
            cell_n[bcell[i]] = 0      # the build is done: empty the cells for the next one
        dt = cfg[b, DT]
        thick = cfg[b, THICK]
        pebble = clump[i] >= 0        # its clump carries the weight and integrates
        fx = (0.0 if pebble else mass[i] * cfg[b, GX]) + fext[i, 0]
        fy = (0.0 if pebble else mass[i] * cfg[b, GY]) + fext[i, 1]
        mz = 0.0
        nball = nb.shape[1]
        xi = pos[i, 0]
        yi = pos[i, 1]
        ri = rad[i]
        for k in range(nbn[i]):
            j = nb[k, i]
            p = k * nball + i
            lo = min(i, j)
            hi = max(i, j)
            dx = pos[hi, 0] - pos[lo, 0]
            dy = pos[hi, 1] - pos[lo, 1]
            d2 = dx * dx + dy * dy
            rlo = rad[lo]
            rhi = rad[hi]
            rs = rlo + rhi
            if d2 >= rs * rs:
                for c in range(HW):        # the contact opened: its history restarts
                    nh[p, c] = 0.0
                continue
            d = math.sqrt(d2)
            nx = dx / d
            ny = dy / d
            c = row(coef, b, mat[lo], mat[hi])
            gx, gy, mlo, mhi, fn, ft, e1, e2, e3 = contact_force(
                LAW, c, nx, ny, rs - d, vel[hi, 0] - vel[lo, 0], vel[hi, 1] - vel[lo, 1],
                omega[lo], omega[hi], rlo, rhi, minv[lo], minv[hi], thick, dt, nh, p)
            if i == hi:
                fx += gx
                fy += gy
                mz += mhi
            else:
                fx -= gx
                fy -= gy
                mz += mlo
        for k in range(wln[i]):
            s = wl[k, i]
            q = k * nball + i
            px, py, d2 = wall_contact_point(pos, i, seg, link, s)
            if d2 >= ri * ri or d2 == 0.0:
                for c in range(HW):
                    wh[q, c] = 0.0
                continue
            d = math.sqrt(d2)
            nx = (xi - px) / d
            ny = (yi - py) / d
            wx = wvel[s, 0] - womega[s] * (py - centre[s, 1])
            wy = wvel[s, 1] + womega[s] * (px - centre[s, 0])
            c = row(coef, b, wmat[s], mat[i])
            gx, gy, mw, mb, fn, ft, e1, e2, e3 = contact_force(
                LAW, c, nx, ny, ri - d, vel[i, 0] - wx, vel[i, 1] - wy, 0.0, omega[i],
                0.0, ri, 0.0, minv[i], thick, dt, wh, q)
            fx += gx
            fy += gy
            mz += mb
            cuda.atomic.add(wforce, (s, 0), -gx)
            cuda.atomic.add(wforce, (s, 1), -gy)
            cuda.atomic.add(wmoment, s, -((px - centre[s, 0]) * gy - (py - centre[s, 1]) * gx))
        eacc = cuda.local.array(6, dtype=nh.dtype)    # energies: not booked on the GPU yet
        for k in range(bln[i]):
            q = bl[k, i]
            side = 0 if bij[0, q] == i else 1
            if bactive[side, q] == 0:
                continue
            gone, gx, gy, m = flat_joint(q, side, pos, vel, omega, rad, dt, thick, bij, bc, bsc,
                                         bstate, bfn, bfs, bactive, clock[b], logi, logf,
                                         logn, eacc)
            fx += gx
            fy += gy
            mz += m
            if gone:
                relist[b] = 1         # the pair enters the contact list at once
        if pebble:
            force[i, 0] = fx
            force[i, 1] = fy
            force[i, 2] = mz
            return
        f = fix[i]
        alpha = damp[i]
        if alpha > 0.0:
            if not (f & 1):
                fx = locally_damped(fx, vel[i, 0], alpha)
            if not (f & 2):
                fy = locally_damped(fy, vel[i, 1], alpha)
            if not (f & 4):
                mz = locally_damped(mz, omega[i], alpha)
        force[i, 0] = fx
        force[i, 1] = fy
        force[i, 2] = mz
        # the full-step velocity goes to vend/wend: vel/omega (the half step) are read by
        # the threads of this ball's neighbours while this one runs
        h = 0.5 * dt
        vx = vel[i, 0] if f & 1 else vel[i, 0] + h * fx * minv[i]
        vy = vel[i, 1] if f & 2 else vel[i, 1] + h * fy * minv[i]
        wz = omega[i] if f & 4 else omega[i] + h * mz * iinv[i]
        vend[i, 0] = vx
        vend[i, 1] = vy
        wend[i] = wz
        if not in_domain(cfg, b, xi, yi, vx, vy, wz):
            cuda.atomic.or_(err, b, ERR_GUARD)

    @cuda.jit(device=True, inline=True)
    def in_domain(cfg, b, x, y, vx, vy, w):
        """The guards of integrate.in_domain (NaN fails every comparison)."""
        return ((x >= cfg[b, X0]) and (x <= cfg[b, X1]) and (y >= cfg[b, Y0])
                and (y <= cfg[b, Y1]) and (vx * vx + vy * vy <= cfg[b, VMAX2])
                and abs(w) < 1e300)

    @cuda.jit(device=True, inline=True)
    def place_pebbles(c, cpos, cvel, comega, ctheta, pstart, pidx, offset, alive, pos, vel,
                      omega):
        """Pebbles of clump c at the clump's rigid motion (clumps.place_pebbles)."""
        cs = math.cos(ctheta[c])
        sn = math.sin(ctheta[c])
        for k in range(pstart[c], pstart[c + 1]):
            i = pidx[k]
            if alive[i] == 0:
                continue
            pos[i, 0], pos[i, 1], vel[i, 0], vel[i, 1] = pebble_motion(
                cpos[c, 0], cpos[c, 1], cvel[c, 0], cvel[c, 1], comega[c], cs, sn,
                offset[i, 0], offset[i, 1])
            omega[i] = comega[c]

    @cuda.jit
    def clumps_first(cpos, cvel, comega, ctheta, cmass, cinertia, cheld, cforce, cmoment,
                     ccase, cfg, pstart, pidx, offset, alive, pos, vel, omega, pos0, travel,
                     need, halt):
        """First half of the step of clump c (integrate.clumps_kick_drift), its pebbles
        placed (half-step velocities) and checked against the skin like free balls."""
        c = cuda.grid(1)
        if c >= cpos.shape[0] or halt[ccase[c]] != 0:
            return
        b = ccase[c]
        dt = cfg[b, DT]
        h = 0.5 * dt
        if not cheld[c]:
            cvel[c, 0] += h * cforce[c, 0] / cmass[c]
            cvel[c, 1] += h * cforce[c, 1] / cmass[c]
            comega[c] += h * cmoment[c] / cinertia[c]
        cpos[c, 0] += dt * cvel[c, 0]
        cpos[c, 1] += dt * cvel[c, 1]
        ctheta[c] += dt * comega[c]
        place_pebbles(c, cpos, cvel, comega, ctheta, pstart, pidx, offset, alive, pos, vel,
                      omega)
        for k in range(pstart[c], pstart[c + 1]):
            i = pidx[k]
            dx = pos[i, 0] - pos0[i, 0]
            dy = pos[i, 1] - pos0[i, 1]
            if alive[i] and 2.0 * math.sqrt(dx * dx + dy * dy) + travel[b] > cfg[b, SKIN]:
                need[b] = 1

    @cuda.jit
    def clumps_second(cpos, cvel, comega, ctheta, cmass, cinertia, cheld, cforce, cmoment,
                      cdamp, ccase, cfg, pstart, pidx, offset, alive, pos, force, vend, wend,
                      err, halt):
        """Second half of clump c: weight plus its pebbles' forces and moments (in ball
        order, as gather_clumps), local damping and half kick unless held, its pebbles'
        full-step velocities."""
        c = cuda.grid(1)
        if c >= cpos.shape[0] or halt[ccase[c]] != 0:
            return
        b = ccase[c]
        h = 0.5 * cfg[b, DT]
        fx = cmass[c] * cfg[b, GX]
        fy = cmass[c] * cfg[b, GY]
        mz = 0.0
        for k in range(pstart[c], pstart[c + 1]):
            i = pidx[k]
            if alive[i] == 0:
                continue
            fx += force[i, 0]
            fy += force[i, 1]
            mz += force[i, 2] + (pos[i, 0] - cpos[c, 0]) * force[i, 1] \
                - (pos[i, 1] - cpos[c, 1]) * force[i, 0]
        if not cheld[c]:
            alpha = cdamp[c]
            if alpha > 0.0:
                fx = locally_damped(fx, cvel[c, 0], alpha)
                fy = locally_damped(fy, cvel[c, 1], alpha)
                mz = locally_damped(mz, comega[c], alpha)
            cvel[c, 0] += h * fx / cmass[c]
            cvel[c, 1] += h * fy / cmass[c]
            comega[c] += h * mz / cinertia[c]
        cforce[c, 0] = fx
        cforce[c, 1] = fy
        cmoment[c] = mz
        place_pebbles(c, cpos, cvel, comega, ctheta, pstart, pidx, offset, alive, pos, vend,
                      wend)
        for k in range(pstart[c], pstart[c + 1]):
            i = pidx[k]
            if alive[i] and not in_domain(cfg, b, pos[i, 0], pos[i, 1], vend[i, 0], vend[i, 1],
                                          wend[i]):
                cuda.atomic.or_(err, b, ERR_GUARD)

    @cuda.jit
    def cases_step(halt, left, clock, step0, cfg, dtc, prm, cpos, cvel, comega, cforce, cmass,
                   cheld, seg, wforce, wvel, ccfg, csens, cmemb, cscale, cact, cctl, ccpar,
                   ccst, cval, cwsum, csamp, cdim):
        """The end of a step, per running case (the CPU's order: engine.run_steps): its time
        advances, its automatic dt takes this step's rebuild's dt_crit, its controllers run
        (an event halts it), its budget counts down (halted when spent)."""
        b = cuda.grid(1)
        if b >= halt.shape[0] or halt[b] != RUNNING:
            return
        prm[b, P.TIME] += prm[b, P.DT]
        if dtc[b] < NO_DT:
            if cfg[b, AUTO] > 0.0:
                cfg[b, DT] = cfg[b, SAFETY] * dtc[b]
                prm[b, P.DT] = cfg[b, DT]
            dtc[b] = NO_DT
        if ccfg[b, EVERY] > 0 and case_control(
                b, prm, step0[b] + clock[b], False, cpos, cvel, comega, cforce, cmass, cheld,
                seg, wforce, wvel, ccfg, csens, cmemb, cscale, cact, cctl, ccpar, ccst, cval,
                cwsum, csamp, cdim):
            halt[b] = HALT_EVENT
        left[b] -= 1
        if left[b] <= 0 and halt[b] == RUNNING:
            halt[b] = HALT_STEPS

    @cuda.jit
    def cases_resume(halt, prm, cpos, cvel, comega, cforce, cmass, cheld, seg, wforce, wvel,
                     ccfg, csens, cmemb, cscale, cact, cctl, ccpar, ccst, cval, cwsum, csamp,
                     cdim):
        """Before a resumed case's first step: its pending velocities (as a CPU run starts)."""
        b = cuda.grid(1)
        if b < halt.shape[0] and halt[b] == RUNNING and ccfg[b, EVERY] > 0:
            case_control(b, prm, 0, True, cpos, cvel, comega, cforce, cmass, cheld, seg, wforce,
                         wvel, ccfg, csens, cmemb, cscale, cact, cctl, ccpar, ccst, cval,
                         cwsum, csamp, cdim)

    return dict(walls_step=walls_step, first_half=first_half, bin=bin_balls, build=build,
                ball_springs=ball_springs, unbin=unbin, forces=forces, clumps_first=clumps_first,
                clumps_second=clumps_second, cases_step=cases_step, cases_resume=cases_resume)
