"""Neighbour search: cell list + Verlet lists, O(N) per build.

Pair lists are kept sorted by (i, j) so that contact history survives a rebuild by a
linear merge with the previous list, and so that forces are always summed in the same
order (bitwise reproducible whatever the rebuild timing).
"""
import numpy as np
from numba import njit


@njit(cache=True)
def _cell_of(x, y, xmin, ymin, cs, ncx, ncy):
    cx = int((x - xmin) / cs)
    cy = int((y - ymin) / cs)
    cx = min(max(cx, 0), ncx - 1)   # balls outside the domain are caught by the guards
    cy = min(max(cy, 0), ncy - 1)
    return cx, cy


@njit(cache=True)
def build_pairs(pos, rad, alive, clump, skin, xmin, ymin, xmax, ymax, out_i, out_j):
    """Fill out_i/out_j with pairs i < j closer than r_i + r_j + skin (sorted).
    Pebbles of one clump are skipped. Returns the count, or -needed if over capacity."""
    n = pos.shape[0]
    rmax = 0.0
    for i in range(n):
        if alive[i] and rad[i] > rmax:
            rmax = rad[i]
    cs = 2.0 * rmax + skin
    ncx = max(1, int((xmax - xmin) / cs))
    ncy = max(1, int((ymax - ymin) / cs))
    cs = max((xmax - xmin) / ncx, (ymax - ymin) / ncy)
    ncx = max(1, int((xmax - xmin) / cs) + 1)
    ncy = max(1, int((ymax - ymin) / cs) + 1)
    # counting sort of balls into cells
    start = np.zeros(ncx * ncy + 1, np.int64)
    cell = np.empty(n, np.int64)
    for i in range(n):
        if alive[i]:
            cx, cy = _cell_of(pos[i, 0], pos[i, 1], xmin, ymin, cs, ncx, ncy)
            cell[i] = cy * ncx + cx
            start[cell[i] + 1] += 1
        else:
            cell[i] = -1
    for c in range(ncx * ncy):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    items = np.empty(n, np.int64)
    for i in range(n):          # ascending i inside each cell
        if cell[i] >= 0:
            items[fill[cell[i]]] = i
            fill[cell[i]] += 1
    cap = out_i.shape[0]
    cnt = 0
    buf = np.empty(256, np.int64)
    for i in range(n):
        if cell[i] < 0:
            continue
        cx = cell[i] % ncx
        cy = cell[i] // ncx
        nb = 0
        for dy in range(-1, 2):
            yy = cy + dy
            if yy < 0 or yy >= ncy:
                continue
            for dx in range(-1, 2):
                xx = cx + dx
                if xx < 0 or xx >= ncx:
                    continue
                c = yy * ncx + xx
                for q in range(start[c], start[c + 1]):
                    j = items[q]
                    if j <= i:
                        continue
                    if clump[i] >= 0 and clump[i] == clump[j]:
                        continue
                    ddx = pos[j, 0] - pos[i, 0]
                    ddy = pos[j, 1] - pos[i, 1]
                    cut = rad[i] + rad[j] + skin
                    if ddx * ddx + ddy * ddy < cut * cut:
                        if nb == buf.shape[0]:
                            nbuf = np.empty(2 * nb, np.int64)
                            nbuf[:nb] = buf
                            buf = nbuf
                        buf[nb] = j
                        nb += 1
        # insertion sort: rows are short
        for a in range(1, nb):
            v = buf[a]
            b = a - 1
            while b >= 0 and buf[b] > v:
                buf[b + 1] = buf[b]
                b -= 1
            buf[b + 1] = v
        for a in range(nb):
            if cnt < cap:
                out_i[cnt] = i
                out_j[cnt] = buf[a]
            cnt += 1
    if cnt > cap:
        return -cnt
    return cnt


@njit(cache=True)
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


@njit(cache=True)
def build_wall_pairs(pos, rad, alive, seg, skin, out_i, out_s):
    """Ball-segment pairs closer than r + skin, sorted by (ball, segment).
    Returns the count or -needed. O(N * segments): segments are few in a rig."""
    cap = out_i.shape[0]
    cnt = 0
    for i in range(pos.shape[0]):
        if not alive[i]:
            continue
        for s in range(seg.shape[0]):
            cx, cy, u = seg_closest(pos[i, 0], pos[i, 1], seg[s, 0], seg[s, 1], seg[s, 2], seg[s, 3])
            dx = pos[i, 0] - cx
            dy = pos[i, 1] - cy
            cut = rad[i] + skin
            if dx * dx + dy * dy < cut * cut:
                if cnt < cap:
                    out_i[cnt] = i
                    out_s[cnt] = s
                cnt += 1
    if cnt > cap:
        return -cnt
    return cnt


@njit(cache=True)
def merge_history(old_i, old_j, old_h, n_old, new_i, new_j, n_new, out_h):
    """out_h[k] = history of (new_i[k], new_j[k]) in the old sorted list, else 0."""
    a = 0
    for k in range(n_new):
        while a < n_old and (old_i[a] < new_i[k] or (old_i[a] == new_i[k] and old_j[a] < new_j[k])):
            a += 1
        if a < n_old and old_i[a] == new_i[k] and old_j[a] == new_j[k]:
            for c in range(out_h.shape[1]):
                out_h[k, c] = old_h[a, c]
        else:
            for c in range(out_h.shape[1]):
                out_h[k, c] = 0.0


@njit(cache=True)
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


@njit(cache=True)
def rebuild(pos, rad, alive, clump, pos0, skin, xmin, ymin, xmax, ymax,
            p_i, p_j, p_h, p_bond, p_n, bond_i, bond_j, seg, w_i, w_s, w_h, w_n):
    """Rebuild both Verlet lists in place, carrying the contact history over.
    Returns (0, 0), or (1 | 2, needed) if the pair | wall-pair arrays are too small
    (lists untouched)."""
    n_old = p_n[0]
    new_i = np.empty(p_i.shape[0], np.int32)
    new_j = np.empty(p_i.shape[0], np.int32)
    cnt = build_pairs(pos, rad, alive, clump, skin, xmin, ymin, xmax, ymax, new_i, new_j)
    if cnt < 0:
        return 1, -cnt
    wn_old = w_n[0]
    nw_i = np.empty(w_i.shape[0], np.int32)
    nw_s = np.empty(w_i.shape[0], np.int32)
    wcnt = build_wall_pairs(pos, rad, alive, seg, skin, nw_i, nw_s)
    if wcnt < 0:
        return 2, -wcnt
    old_h = p_h[:n_old].copy()
    merge_history(p_i, p_j, old_h, n_old, new_i, new_j, cnt, p_h)
    for k in range(cnt):
        p_i[k] = new_i[k]
        p_j[k] = new_j[k]
        p_bond[k] = find_bond(bond_i, bond_j, new_i[k], new_j[k])
    p_n[0] = cnt
    old_wh = w_h[:wn_old].copy()
    merge_history(w_i, w_s, old_wh, wn_old, nw_i, nw_s, wcnt, w_h)
    for k in range(wcnt):
        w_i[k] = nw_i[k]
        w_s[k] = nw_s[k]
    w_n[0] = wcnt
    for i in range(pos.shape[0]):
        pos0[i, 0] = pos[i, 0]
        pos0[i, 1] = pos[i, 1]
    return 0, 0


@njit(cache=True)
def grow_rows(a, n):
    """Copy of ``a`` with ``n`` rows (new rows zero)."""
    out = np.zeros((n,) + a.shape[1:], a.dtype)
    out[: a.shape[0]] = a
    return out
