"""Neighbour search: cell list + Verlet lists, O(N) per build.

Pair lists are grouped by i (ascending) so that contact history survives a rebuild by a
search in the short old row of i. The order only depends on the positions at the build,
so a run is bitwise reproducible (the checkpoint keeps the list and the build positions).
"""
import math

import numpy as np
from numba import njit

from . import params as P


@njit(cache=True, error_model="numpy")
def build_pairs(pos, rad, alive, buried, clump, skin, xmin, ymin, xmax, ymax, out_i, out_j):
    """Fill out_i/out_j with pairs i < j closer than r_i + r_j + skin, grouped by i
    (ascending). Pebbles of one clump are skipped, buried ones too (the cells are sized
    over every live ball all the same: the order of the pairs left does not change).
    Returns the count, or -needed if over capacity.

    Cells of side >= 2 r_max + skin; a half stencil (own cell + 4 neighbours) visits each
    pair once from cell-ordered copies of the coordinates (cache friendly); the pairs are
    then counting-sorted by i."""
    n = pos.shape[0]
    rmax = 0.0
    for i in range(n):
        if alive[i] and rad[i] > rmax:
            rmax = rad[i]
    cs = 2.0 * rmax + skin
    ncx = max(1, int((xmax - xmin) / cs))
    ncy = max(1, int((ymax - ymin) / cs))
    csx = (xmax - xmin) / ncx
    csy = (ymax - ymin) / ncy
    start = np.zeros(ncx * ncy + 1, np.int64)
    cell = np.empty(n, np.int64)
    for i in range(n):
        if alive[i] and not buried[i]:
            cx = min(max(int((pos[i, 0] - xmin) / csx), 0), ncx - 1)
            cy = min(max(int((pos[i, 1] - ymin) / csy), 0), ncy - 1)
            cell[i] = cy * ncx + cx
            start[cell[i] + 1] += 1
        else:
            cell[i] = -1
    for c in range(ncx * ncy):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    m = start[ncx * ncy]
    ids = np.empty(m, np.int64)
    xs = np.empty(m)
    ys = np.empty(m)
    rs = np.empty(m)
    cl = np.empty(m, np.int64)
    for i in range(n):
        c = cell[i]
        if c >= 0:
            q = fill[c]
            ids[q] = i
            xs[q] = pos[i, 0]
            ys[q] = pos[i, 1]
            rs[q] = rad[i]
            cl[q] = clump[i]
            fill[c] = q + 1
    # pass 1: pairs as (min, max) in cell order, into scratch. Branch-free append (write
    # always, advance by the test): the in/out test is unpredictable, the store is cheap.
    cap = out_i.shape[0]
    room = max(cap, 16)
    pa = np.empty(room + 1, np.int64)
    pb = np.empty(room + 1, np.int64)
    cnt = 0
    for cy in range(ncy):
        for cx in range(ncx):
            c = cy * ncx + cx
            for q in range(start[c], start[c + 1]):
                xq = xs[q]
                yq = ys[q]
                rq = rs[q] + skin
                cq = cl[q]
                iq = ids[q]
                # half stencil as two contiguous ranges of the cell-ordered arrays: the rest
                # of the own cell + the right neighbour, and the three cells of the row above
                for part in range(2):
                    if part == 0:
                        lo = q + 1
                        hi = start[c + 2] if cx + 1 < ncx else start[c + 1]
                    else:
                        if cy + 1 >= ncy:
                            break
                        up = (cy + 1) * ncx
                        lo = start[up + max(cx - 1, 0)]
                        hi = start[up + min(cx + 1, ncx - 1) + 1]
                    for r in range(lo, hi):
                        ddx = xs[r] - xq
                        ddy = ys[r] - yq
                        cut = rq + rs[r]
                        hit = (ddx * ddx + ddy * ddy < cut * cut) & ((cq < 0) | (cq != cl[r]))
                        k = min(cnt, room)
                        ir = ids[r]
                        pa[k] = min(iq, ir)
                        pb[k] = max(iq, ir)
                        cnt += 1 if hit else 0
    if cnt > cap:
        return -cnt
    # pass 2: counting sort by i (rows in a deterministic order; j order within a row
    # follows the cell traversal, which only depends on the positions)
    row = np.zeros(n + 1, np.int64)
    for k in range(cnt):
        row[pa[k] + 1] += 1
    for i in range(n):
        row[i + 1] += row[i]
    for k in range(cnt):
        i = pa[k]
        out_i[row[i]] = i
        out_j[row[i]] = pb[k]
        row[i] += 1
    return cnt


@njit(cache=True, error_model="numpy")
def seg_closest(px, py, x0, y0, x1, y1):
    """Closest point of segment (x0,y0)-(x1,y1) to (px,py) and its parameter u in [0,1]."""
    ex = x1 - x0
    ey = y1 - y0
    ll = ex * ex + ey * ey
    u = 0.0
    if ll > 0.0:
        u = ((px - x0) * ex + (py - y0) * ey) / ll
        u = min(max(u, 0.0), 1.0)
    return x0 + u * ex, y0 + u * ey, u


@njit(cache=True, error_model="numpy")
def build_wall_pairs(pos, rad, alive, buried, seg, skin, out_i, out_s, clear):
    """Ball-segment pairs closer than r + skin, sorted by (ball, segment); buried pebbles
    have none.
    clear[i] = a lower bound of the gap between ball i and every segment NOT listed with
    it (>= skin): ball i cannot touch a new segment before moving clear[i] minus the wall
    travel. Returns the count or -needed. O(N * segments): segments are few in a rig."""
    cap = out_i.shape[0]
    ns = seg.shape[0]
    rmax = 0.0
    for i in range(pos.shape[0]):
        if alive[i] and rad[i] > rmax:
            rmax = rad[i]
    # bounding boxes of the segments grown by r_max + skin: a cheap reject before the
    # exact distance (most balls are far from most segments)
    box = np.empty((ns, 4))
    for s in range(ns):
        g = rmax + skin
        box[s, 0] = min(seg[s, 0], seg[s, 2]) - g
        box[s, 1] = min(seg[s, 1], seg[s, 3]) - g
        box[s, 2] = max(seg[s, 0], seg[s, 2]) + g
        box[s, 3] = max(seg[s, 1], seg[s, 3]) + g
    cnt = 0
    for i in range(pos.shape[0]):
        clear[i] = 1.0e30
        if not alive[i] or buried[i]:
            continue
        px = pos[i, 0]
        py = pos[i, 1]
        for s in range(ns):
            if px < box[s, 0] or px > box[s, 2] or py < box[s, 1] or py > box[s, 3]:
                # outside the grown box: farther than r_max + skin from the segment
                clear[i] = min(clear[i], rmax + skin - rad[i])
                continue
            cx, cy, u = seg_closest(px, py, seg[s, 0], seg[s, 1], seg[s, 2], seg[s, 3])
            dx = px - cx
            dy = py - cy
            cut = rad[i] + skin
            d2 = dx * dx + dy * dy
            if d2 < cut * cut:
                if cnt < cap:
                    out_i[cnt] = i
                    out_s[cnt] = s
                cnt += 1
            else:
                clear[i] = min(clear[i], math.sqrt(d2) - rad[i])
    if cnt > cap:
        return -cnt
    return cnt


@njit(cache=True, error_model="numpy")
def match_rows(old_i, old_j, n_old, new_i, new_j, n_new, n_rows):
    """found[k] = row of (new_i[k], new_j[k]) in the old list (grouped by i), else -1.
    Rows are short, so a linear search in the old row of i is the fastest match."""
    row = np.zeros(n_rows + 1, np.int64)
    for a in range(n_old):
        row[old_i[a] + 1] += 1
    for i in range(n_rows):
        row[i + 1] += row[i]
    found = np.full(n_new, -1, np.int64)
    for k in range(n_new):
        j = new_j[k]
        for a in range(row[new_i[k]], row[new_i[k] + 1]):
            if old_j[a] == j:
                found[k] = a
                break
    return found


@njit(cache=True, error_model="numpy")
def carry_rows(found, old, out):
    """out[k] = old[found[k]] (zero where found[k] < 0), rows of a 1- or 2-D array."""
    for k in range(found.shape[0]):
        if found[k] >= 0:
            out[k] = old[found[k]]
        else:
            out[k] = 0.0


@njit(cache=True, error_model="numpy")
def find_bond(bi, bj, i, j):
    """Index of bond (i, j) in the (i, j)-sorted bond arrays, or -1 (binary search)."""
    lo = 0
    hi = bi.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if bi[mid] < i or (bi[mid] == i and bj[mid] < j):
            lo = mid + 1
        else:
            hi = mid
    if lo < bi.shape[0] and bi[lo] == i and bj[lo] == j:
        return lo
    return -1


@njit(cache=True, error_model="numpy")
def _drop_flat_jointed(new_i, new_j, cnt, bonds, out_bond):
    """Remove the pairs held by an active flat joint from the new list (in place, order
    kept; returns the new count) and write each kept pair's bond (or -1) to ``out_bond``.
    A flat joint replaces the contact, so the contact loop need not visit them (in a
    bonded packing most pairs are bonded: 1727 of 2341 in the thesis box case); the
    bond's removal forces a rebuild (bonds.py), which brings the pair back as a contact."""
    nb = bonds.i.shape[0]
    m = 0
    for k in range(cnt):
        b = find_bond(bonds.i, bonds.j, new_i[k], new_j[k]) if nb > 0 else -1
        if b >= 0 and bonds.active[b]:
            continue
        new_i[m] = new_i[k]
        new_j[m] = new_j[k]
        out_bond[m] = b
        m += 1
    return m


@njit(cache=True, error_model="numpy")
def rebuild(prm, balls, pr, wp, bonds, seg):
    """Rebuild both Verlet lists in place from ``balls.pos``, carrying the per-contact
    columns (history and state) over. Returns (0, 0), or (1 | 2, needed) if the pair |
    wall-pair arrays are too small (lists untouched)."""
    pos = balls.pos
    skin = prm[P.SKIN]
    n_old = pr.n[0]
    new_i = np.empty(pr.i.shape[0], np.int32)
    new_j = np.empty(pr.i.shape[0], np.int32)
    cnt = build_pairs(pos, balls.rad, balls.alive, balls.buried, balls.clump, skin, prm[P.XMIN],
                      prm[P.YMIN], prm[P.XMAX], prm[P.YMAX], new_i, new_j)
    if cnt < 0:
        return 1, -cnt
    wn_old = wp.n[0]
    nw_i = np.empty(wp.i.shape[0], np.int32)
    nw_s = np.empty(wp.i.shape[0], np.int32)
    wcnt = build_wall_pairs(pos, balls.rad, balls.alive, balls.buried, seg, skin, nw_i, nw_s, balls.clear)
    if wcnt < 0:
        return 2, -wcnt
    cnt = _drop_flat_jointed(new_i, new_j, cnt, bonds, pr.bond)   # match_rows reads no bond
    found = match_rows(pr.i, pr.j, n_old, new_i, new_j, cnt, pos.shape[0])
    carry_rows(found, pr.hist[:n_old].copy(), pr.hist)
    carry_rows(found, pr.lap0[:n_old].copy(), pr.lap0)
    for k in range(cnt):
        pr.i[k] = new_i[k]
        pr.j[k] = new_j[k]
    pr.n[0] = cnt
    found = match_rows(wp.i, wp.s, wn_old, nw_i, nw_s, wcnt, pos.shape[0])
    carry_rows(found, wp.hist[:wn_old].copy(), wp.hist)
    for k in range(wcnt):
        wp.i[k] = nw_i[k]
        wp.s[k] = nw_s[k]
    wp.n[0] = wcnt
    for i in range(pos.shape[0]):
        balls.pos0[i, 0] = pos[i, 0]
        balls.pos0[i, 1] = pos[i, 1]
    return 0, 0


@njit(cache=True, error_model="numpy")
def grow_rows(a, n):
    """Copy of ``a`` with ``n`` rows (new rows zero)."""
    out = np.zeros((n,) + a.shape[1:], a.dtype)
    out[: a.shape[0]] = a
    return out
