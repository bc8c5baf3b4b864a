"""How the GPU batch lays its cases out in host arrays (``pack``: balls, segments, flat
joints, clumps and controllers of all cases end to end, with each case's offsets, cell grid
and scalars) and how a case's rows go back into its simulation's Verlet lists
(``lists_to_cpu``). The device arrays are these, copied once (batch.Batch)."""
import math

import numpy as np

from .. import params as P
from ..control import CLUMP_POSITION, CLUMP_REACTION, HELD_CLUMP, NCFG, NPAR, NST, Control
from ..state import Pairs, WallPairs
from . import kernels as K

MAX_NEIGHBOURS = 24     # full-list slots per ball (disks of size ratio <= 2 with a skin
MAX_WALLS = 4           # of 0.25 d_max have at most ~15); overflow is an error, not a loss
MAX_BONDS = 12          # flat joints per ball (11 in bonded settle2d, gap factor 2.5)


class BatchError(ValueError):
    """A case the batch cannot run, or a case that failed while running."""


# the device arrays to_simulations reads, by the range of a case that indexes them
BALL_ROWS = ("pos", "vend", "wend", "force", "minv", "iinv", "nbn", "wln")
SEGMENT_ROWS = ("seg", "centre", "wforce", "wmoment", "wvel")
CLUMP_ROWS = ("cpos", "cheld", "cvel", "comega", "ctheta", "cforce", "cmoment")
BOND_ROWS = ("bsc", "bstate", "bfn", "bfs", "bactive")     # side 0's copy


def lists_to_cpu(h, sim, lo, w0):
    """A case's contacts and their history (its rows ``h``: balls from global index lo,
    segments from w0) as the CPU's Verlet lists (i < j, grouped by i), which its next
    rebuild (flagged here) carries over."""
    width = h["nh"].shape[2]
    nball = h["nbn"].shape[0]
    use = np.arange(MAX_NEIGHBOURS)[None, :] < h["nbn"][:, None]
    i = np.broadcast_to(np.arange(nball)[:, None], use.shape)
    j = h["nb"].T - lo
    keep = use & (j > i)
    n = int(keep.sum())
    pr = Pairs.empty(max(n, 1), width)
    pr.i[:n] = i[keep]
    pr.j[:n] = j[keep]
    pr.hist[:n] = h["nh"].transpose(1, 0, 2)[keep]
    pr.n[0] = n
    wuse = np.arange(MAX_WALLS)[None, :] < h["wln"][:, None]
    wi = np.broadcast_to(np.arange(nball)[:, None], wuse.shape)
    m = int(wuse.sum())
    wp = WallPairs.empty(max(m, 1), width)
    wp.i[:m] = wi[wuse]
    wp.s[:m] = h["wl"].T[wuse] - w0
    wp.hist[:m] = h["wh"].transpose(1, 0, 2)[wuse]
    wp.n[0] = m
    sim.pairs, sim.wpairs = pr, wp
    sim.cnt[2] = 1       # rebuilt (history carried) before the next CPU step


def pack(sims, controls):
    """Host arrays of the batch: the cases' balls and segments end to end, their
    controllers, each case's parameters, step and budget."""
    nball = [len(s.balls) for s in sims]
    nseg = [len(s.walls) for s in sims]
    offsets = np.concatenate([[0], np.cumsum(nball)]).astype(np.int64)
    woff = np.concatenate([[0], np.cumsum(nseg)]).astype(np.int64)
    def cat(name, part):
        return np.ascontiguousarray(np.concatenate([getattr(getattr(s, part), name)
                                                    for s in sims]))

    h = {n: cat(n, "balls") for n in ("pos", "vel", "omega", "rad", "mass", "inertia",
                                      "minv", "iinv", "damp", "fext")}
    h["fix"] = cat("fix", "balls").astype(np.int32)
    h["mat"] = cat("mat", "balls").astype(np.int32)
    h["alive"] = cat("alive", "balls").astype(np.uint8)
    h["force"] = np.concatenate([np.column_stack([s.balls.force, s.balls.moment]) for s in sims])
    h["case"] = np.repeat(np.arange(len(sims), dtype=np.int32), nball)
    h["pos0"] = h["pos"].copy()
    h["vend"] = h["vel"].copy()         # full-step velocities (vel: the half step's)
    h["wend"] = h["omega"].copy()
    n = len(h["case"])
    width = max(int(sims[0].law.width), 1)
    h["nb"] = np.full((MAX_NEIGHBOURS, n), -1, np.int32)   # slot-major: see kernels.py
    h["nbn"] = np.zeros(n, np.int32)
    h["nh"] = np.zeros((n * MAX_NEIGHBOURS, width))
    h["wl"] = np.full((MAX_WALLS, n), -1, np.int32)
    h["wln"] = np.zeros(n, np.int32)
    h["wh"] = np.zeros((n * MAX_WALLS, width))
    h["bcell"] = np.zeros(n, np.int32)
    for key in ("nb", "nh", "wl", "wh"):       # the build's new rows (kernels.build)
        h[key + "2"] = np.zeros_like(h[key])
    for b, s in enumerate(sims):        # the CPU's contact history, carried by the first build
        _rows_from_cpu(s, offsets[b], woff[b], h)
    for name in ("seg", "vel", "omega", "centre", "mat"):
        key = {"vel": "wvel", "omega": "womega", "mat": "wmat"}.get(name, name)
        h[key] = np.ascontiguousarray(np.concatenate([getattr(s.walls, name) for s in sims]))
    h["wmat"] = h["wmat"].astype(np.int32)
    h["link"] = np.concatenate([np.where(s.walls.link >= 0, s.walls.link + woff[b], -1)
                                for b, s in enumerate(sims)]).astype(np.int32).reshape(-1, 2)
    h["wcase"] = np.repeat(np.arange(len(sims), dtype=np.int32), nseg)
    h["wforce"] = np.zeros((woff[-1], 2))
    h["wmoment"] = np.zeros(woff[-1])
    h["wlo"] = woff[:-1].astype(np.int32)
    h["whi"] = woff[1:].astype(np.int32)
    cfg, grid, cells, max_cell = _grids(sims)
    h["cfg"], h["grid"] = cfg, grid
    nmat = max(s.coef.shape[0] for s in sims)
    coef = np.zeros((len(sims), nmat, nmat, sims[0].coef.shape[2]))
    for b, s in enumerate(sims):
        m = s.coef.shape[0]
        coef[b, :m, :m] = s.coef
    h["coef"] = coef
    h["need"] = np.ones(len(sims), np.int32)     # build every case before the first step
    h["travel"] = np.zeros(len(sims))
    h["err"] = np.zeros(len(sims), np.int32)
    h["offsets"] = offsets
    h["relist"] = np.zeros(len(sims), np.int32)
    h["bond_offsets"] = np.concatenate([[0], np.cumsum([len(s.bonds) for s in sims])])
    h["clock"] = np.zeros(len(sims), np.int64)       # each case's steps in the batch
    h["step0"] = np.array([s.cnt[0] for s in sims], np.int64)
    h["prm"] = np.array([s.prm for s in sims])        # time and what the controllers read
    h["halt"] = np.full(len(sims), K.HALT_STEPS, np.int32)
    h["left"] = np.zeros(len(sims), np.int64)
    h["dtc"] = np.full(len(sims), K.NO_DT)       # a rebuild's dt_crit (kernels.ball_springs)
    _pack_bonds(sims, offsets, h)
    _pack_clumps(sims, offsets, h)
    _pack_controls(controls, woff, h["clump_offsets"], h)
    return h, len(sims), cells, max_cell


# the packed controller arrays, in ControlArrays' order (control.py)
CONTROL_ARRAYS = ("ccfg", "csens", "cmemb", "cscale", "cact", "cctl", "ccpar", "ccst", "cval",
                   "cwsum", "csamp")


def _pack_controls(controls, woff, coff, h):
    """Each case's controllers (a built ``Control`` or None) in rows of padded arrays, one
    row per case (``cdim``: its counts, kernels.N_SENSORS...), wall segments and clumps
    renumbered as the batch's."""
    arrs = [Control.empty() if c is None else c.arrays for c in controls]
    for b, (c, a) in enumerate(zip(controls, arrs)):
        if c is not None and a is None:
            raise BatchError(f"case {b}: its Control is not built")
    dims = np.array([(len(a.sensors), len(a.members), len(a.actuators), len(a.ctl),
                      len(a.samp) if len(a.sensors) else 0) for a in arrs],
                    np.int64).reshape(-1, 5)
    ns, nm, na, nk, cap = (max(int(v), 1) for v in dims.max(axis=0, initial=0))
    n = len(arrs)
    out = dict(ccfg=np.zeros((n, NCFG), np.int64), csens=np.zeros((n, ns, 4), np.int64),
               cmemb=np.zeros((n, nm), np.int64), cscale=np.zeros((n, ns)),
               cact=np.zeros((n, na, 4), np.int64), cctl=np.zeros((n, nk, 4), np.int64),
               ccpar=np.zeros((n, nk, NPAR)), ccst=np.zeros((n, nk, NST)),
               cval=np.zeros((n, ns)), cwsum=np.zeros((n, ns)),
               csamp=np.zeros((n, cap, ns + 1)))
    for b, a in enumerate(arrs):
        sens = a.sensors.copy()
        on_clump = (sens[:, 0] == CLUMP_REACTION) | (sens[:, 0] == CLUMP_POSITION)
        sens[on_clump, 1] += coff[b]
        act = a.actuators.copy()
        act[act[:, 0] == HELD_CLUMP, 1] += coff[b]
        out["ccfg"][b] = a.cfg
        for key, v in (("csens", sens), ("cmemb", a.members + woff[b]), ("cscale", a.scale),
                       ("cact", act), ("cctl", a.ctl), ("ccpar", a.cpar), ("ccst", a.cst),
                       ("cval", a.val), ("cwsum", a.wsum)):
            out[key][b, :len(v)] = v
    h.update(out)
    h["cdim"] = dims
    h["controls"] = list(controls)


def _pack_clumps(sims, offsets, h):
    """The cases' clumps end to end, each ball's clump (global index or -1) and each
    clump's pebbles (ball ids ascending: ``pidx[pstart[c]:pstart[c + 1]]``)."""
    nc = [len(s.clumps) for s in sims]
    coff = np.concatenate([[0], np.cumsum(nc)]).astype(np.int64)
    for key, name in (("cpos", "pos"), ("cvel", "vel"), ("comega", "omega"),
                      ("ctheta", "theta"), ("cmass", "mass"), ("cinertia", "inertia"),
                      ("cheld", "held"), ("cforce", "force"), ("cmoment", "moment"),
                      ("cdamp", "damp")):
        h[key] = np.ascontiguousarray(np.concatenate([getattr(s.clumps, name) for s in sims]))
    h["ccase"] = np.repeat(np.arange(len(sims), dtype=np.int32), nc)
    clump = np.concatenate([np.where(s.balls.clump >= 0, s.balls.clump + coff[b], -1)
                            for b, s in enumerate(sims)]).astype(np.int32)
    h["clump"] = clump
    h["offset"] = np.ascontiguousarray(np.concatenate([s.balls.offset for s in sims]))
    pebbles = np.flatnonzero(clump >= 0)
    order = np.argsort(clump[pebbles], kind="stable")      # by clump, ball ids ascending
    h["pidx"] = pebbles[order].astype(np.int32)
    h["pstart"] = np.searchsorted(clump[pebbles][order], np.arange(coff[-1] + 1)).astype(np.int32)
    h["clump_offsets"] = coff


def _pack_bonds(sims, offsets, h):
    """The cases' flat joints end to end (ball indices shifted), their state once per
    side (kernels.flat_joint), each ball's list of its joints, an empty breakage log."""
    bonds = [s.bonds for s in sims]
    nb = [len(bd) for bd in bonds]
    ne = max(bd.state.shape[1] for bd in bonds)
    if any(len(bd) and bd.state.shape[1] != ne for bd in bonds):
        raise BatchError("cases with different numbers of flat-joint elements")
    bij = np.concatenate([[bd.i + off, bd.j + off] for bd, off in zip(bonds, offsets)],
                         axis=1).astype(np.int32).reshape(2, -1)
    cols = ("rbar", "d0", "gi", "kn", "ks", "sigc", "coh", "tanphi", "mu")
    h["bij"] = np.ascontiguousarray(bij)
    h["bc"] = np.array([np.concatenate([getattr(bd, c) for bd in bonds]) for c in cols]
                       ).reshape(len(cols), -1)
    one = lambda name: np.concatenate([getattr(bd, name) for bd in bonds])  # noqa: E731
    h["bsc"] = np.repeat(np.column_stack([one("theta"), one("moment")])[None], 2, axis=0)
    for key, name in (("bstate", "state"), ("bfn", "fn"), ("bfs", "fs"), ("bactive", "active")):
        shape = (-1,) if key == "bactive" else (-1, ne)
        v = np.concatenate([getattr(bd, name)[:len(bd)].reshape((len(bd),) + shape[1:])
                            for bd in bonds]).reshape(shape)
        h[key] = np.ascontiguousarray(np.repeat(v[None], 2, axis=0))
    n = h["case"].shape[0]
    rows = np.concatenate([bij[0], bij[1]]).astype(np.int64)
    order, slot = _slots(rows)
    if len(slot) and slot.max() >= MAX_BONDS:
        raise BatchError(f"a ball has more than {MAX_BONDS} flat joints")
    h["bl"] = np.full((MAX_BONDS, n), -1, np.int32)
    h["bl"][slot, rows[order]] = (np.arange(len(rows)) % max(sum(nb), 1))[order]
    h["bln"] = np.bincount(rows, minlength=n).astype(np.int32)
    cap = max(sum(nb) * ne, 1)
    h["logi"] = np.zeros((cap, 4), np.int64)
    h["logf"] = np.zeros((cap, 3))
    h["logn"] = np.zeros(1, np.int64)


def _slots(rows):
    """Order of ``rows`` grouped by row and each entry's slot in its row."""
    order = np.argsort(rows, kind="stable")
    r = rows[order]
    return order, np.arange(len(r)) - np.searchsorted(r, r, "left")


def _rows_from_cpu(sim, off, woff, h):
    """Enter the CPU's Verlet lists (pairs i < j, ball-segment pairs) of one case, with
    their history, into the batch's full per-ball rows."""
    pr, wp = sim.pairs, sim.wpairs
    n, m = int(pr.n[0]), int(wp.n[0])
    a = np.concatenate([pr.i[:n], pr.j[:n]]).astype(np.int64)
    o = np.concatenate([pr.j[:n], pr.i[:n]]).astype(np.int64)
    hist = np.concatenate([pr.hist[:n], pr.hist[:n]])
    total = h["nbn"].shape[0]
    for rows, other, hh, nb, nbn, nh, cap, shift in (
            (a, o, hist, "nb", "nbn", "nh", MAX_NEIGHBOURS, off),
            (wp.i[:m].astype(np.int64), wp.s[:m].astype(np.int64), wp.hist[:m], "wl", "wln",
             "wh", MAX_WALLS, woff)):
        order, slot = _slots(rows)
        if len(slot) and slot.max() >= cap:
            raise BatchError(f"a ball has more than {cap} listed neighbours ({nb})")
        r = rows[order] + off
        h[nb][slot, r] = other[order] + shift
        h[nh][slot * total + r] = hh[order]
        h[nbn][off:off + len(sim.balls)] = np.bincount(rows, minlength=len(sim.balls))


def _grids(sims):
    """Per-case scalars (kernels.NCFG columns) and cell grids: cells of side 2 r_max +
    skin over the case's domain, numbered after the previous cases' cells."""
    cfg = np.zeros((len(sims), K.NCFG))
    grid = np.zeros((len(sims), 3), np.int32)
    start = 0
    max_cell = 4
    for b, s in enumerate(sims):
        p = s.prm
        live = s.balls.alive == 1
        rmax = float(s.balls.rad[live].max())
        rmin = float(s.balls.rad[live].min())
        cs = 2.0 * rmax + p[P.SKIN]
        x0, y0, x1, y1 = (p[P.XMIN], p[P.YMIN], p[P.XMAX], p[P.YMAX])
        ncx = max(1, int(math.ceil((x1 - x0) / cs)))
        ncy = max(1, int(math.ceil((y1 - y0) / cs)))
        scale2 = (p[P.DT] / p[P.DT_SAFETY]) ** 2 if p[P.DSCALE] > 0.0 else 0.0
        cfg[b] = (p[P.DT], p[P.GX], p[P.GY], p[P.THICK], p[P.SKIN], p[P.VMAX] ** 2,
                  x0, y0, x1, y1, cs, scale2, p[P.AUTO_DT], p[P.DT_SAFETY])
        grid[b] = (ncx, ncy, start)
        start += ncx * ncy
        # the most disks of radius rmin whose centres fit one cell (a square lattice
        # bound on the cell side + 2 rmin), with room for overlap
        per_side = int((cs + 2.0 * rmin) / (2.0 * rmin * 0.9)) + 1
        max_cell = max(max_cell, per_side * per_side)
    return cfg, grid, start, max_cell
