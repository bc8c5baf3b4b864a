import math

import numpy as np
import pytest

from ballaststudy.metrics import fragments, stone_solid, void_ratio

R = 0.01
REL = 2e-3     # disks are 64-gons: area low by ~0.16 % of the disk parts


def square_stone(n, spacing, origin=(0.0, 0.0)):
    """n x n balls on a square lattice, bonds between the 4-neighbours."""
    ij = np.array([(a, b) for b in range(n) for a in range(n)])
    pos = np.asarray(origin) + spacing * ij
    idx = np.arange(n * n).reshape(n, n)          # idx[b, a]
    bi = np.concatenate([idx[:, :-1].ravel(), idx[:-1, :].ravel()])
    bj = np.concatenate([idx[:, 1:].ravel(), idx[1:, :].ravel()])
    return pos, np.full(n * n, R), bi, bj


def hex_stone(m, r=R):
    """Regular hexagon of hex-packed disks with m balls per side (spacing 2r), all
    nearest-neighbour bonds."""
    a1, a2 = np.array([2 * r, 0.0]), np.array([r, math.sqrt(3) * r])
    k = m - 1
    pts = [i * a1 + j * a2 for i in range(-k, k + 1) for j in range(-k, k + 1) if abs(i + j) <= k]
    pos = np.array(pts)
    d = np.hypot(*(pos[:, None, :] - pos[None, :, :]).T)
    bi, bj = np.nonzero(np.triu(np.isclose(d, 2 * r)))
    return pos, np.full(len(pos), r), bi, bj


def minkowski(area_c, perim_c, r=R):
    return area_c + perim_c * r + math.pi * r * r


@pytest.mark.parametrize("spacing", [2 * R, 2.2 * R])   # touching and with 0.2 R gaps
def test_square_stone_solid_is_filled_outline(spacing):
    n = 5
    pos, rad, bi, bj = square_stone(n, spacing)
    L = (n - 1) * spacing
    expected = minkowski(L * L, 4 * L)
    got = stone_solid(pos, rad, bi, bj).area
    assert got == pytest.approx(expected, rel=REL), f"measured {got}, expected {expected}"
    disks = n * n * math.pi * R * R
    assert got > disks * 1.2, "intra-stone pores must be solid"


def test_hex_stone_solid():
    pos, rad, bi, bj = hex_stone(4)
    s = 3 * 2 * R
    expected = minkowski(1.5 * math.sqrt(3) * s * s, 6 * s)
    got = stone_solid(pos, rad, bi, bj).area
    assert got == pytest.approx(expected, rel=REL), f"measured {got}, expected {expected}"


def _vr(pos, rad, bi, bj, intact, box):
    n, lab = fragments(len(rad), bi, bj, intact)
    return void_ratio(pos, rad, lab, n, bi, bj, intact, *box)


def test_void_ratio_of_one_square_stone_in_a_region():
    n = 5
    pos, rad, bi, bj = square_stone(n, 2 * R, origin=(0.05, 0.02))
    box = (0.0, 0.2, 0.0, 0.15)                      # region area 0.03 m^2
    out = _vr(pos, rad, bi, bj, np.ones(len(bi), bool), box)
    solid = (2 * R * n) ** 2 - (4 - math.pi) * R * R
    exp_vr = 1 - solid / 0.03
    assert out["void_ratio"] == pytest.approx(exp_vr, rel=1e-3), f"VR measured {out['void_ratio']}, expected {exp_vr}"
    exp_e = (0.03 - solid) / solid
    assert out["void_ratio_e"] == pytest.approx(exp_e, rel=1e-3), f"e measured {out['void_ratio_e']}, expected {exp_e}"
    exp_balls = 1 - n * n * math.pi * R * R / 0.03
    assert out["void_ratio_balls"] == pytest.approx(exp_balls, rel=1e-3), \
        f"ball-based measured {out['void_ratio_balls']}, expected {exp_balls}"
    assert out["area_total"] == pytest.approx(0.03)


def test_region_clips_at_plate_bottom():
    n = 5
    pos, rad, bi, bj = square_stone(n, 2 * R, origin=(0.05, 0.02))
    y_mid = 0.02 + 2 * R * (n - 1) / 2
    out = _vr(pos, rad, bi, bj, np.ones(len(bi), bool), (0.0, 0.2, 0.0, y_mid))
    solid = ((2 * R * n) ** 2 - (4 - math.pi) * R * R) / 2
    a = 0.2 * y_mid
    assert out["area_solid"] == pytest.approx(solid, rel=REL), f"measured {out['area_solid']}, expected {solid}"
    assert out["void_ratio"] == pytest.approx(1 - solid / a, rel=1e-3)


def lens_area(d, r=R):
    return 2 * r * r * math.acos(d / (2 * r)) - 0.5 * d * math.sqrt(4 * r * r - d * d)


def test_pore_enclosed_by_several_stones_stays_void():
    # four separate bars (no bonds between them) framing a square pore: two bars of 9 balls
    # (x 0 .. 16R at y 0 and 16R) and two of 7 between their end balls, overlapping them by
    # delta (a contact); the pore enclosed by the four stones must stay void
    delta = 0.02 * R
    s7 = (12 * R + 2 * delta) / 6
    row = lambda x0, y0, dx, dy, k: [(x0 + i * dx, y0 + i * dy) for i in range(k)]
    parts = [row(0, 0, 2 * R, 0, 9), row(0, 16 * R, 2 * R, 0, 9),
             row(0, 2 * R - delta, 0, s7, 7), row(16 * R, 2 * R - delta, 0, s7, 7)]
    pos, bi, bj, start = [], [], [], 0
    for p in parts:
        pos += p
        bi += list(range(start, start + len(p) - 1))
        bj += list(range(start + 1, start + len(p)))
        start += len(p)
    pos = np.array(pos) + 0.05
    rad = np.full(len(pos), R)
    bi, bj = np.array(bi), np.array(bj)
    out = _vr(pos, rad, bi, bj, np.ones(len(bi), bool), (0.0, 0.3, 0.0, 0.3))
    stadium = lambda length: length * 2 * R + math.pi * R * R
    expected = 2 * stadium(16 * R) + 2 * stadium(6 * s7) - 4 * lens_area(2 * R - delta)
    assert out["area_solid"] == pytest.approx(expected, rel=REL), \
        f"solid measured {out['area_solid']}, expected {expected} (pore between stones filled?)"


def test_broken_stone_opens_its_crack():
    # a 2 x 1 row bonded: solid = stadium; broken bond: two disks only
    pos = np.array([[0.1, 0.1], [0.1 + 2.4 * R, 0.1]])
    rad = np.full(2, R)
    bi, bj = np.array([0]), np.array([1])
    box = (0.0, 0.3, 0.0, 0.3)
    whole = _vr(pos, rad, bi, bj, np.array([True]), box)["area_solid"]
    broken = _vr(pos, rad, bi, bj, np.array([False]), box)["area_solid"]
    assert whole == pytest.approx(2.4 * R * 2 * R + math.pi * R * R, rel=REL), f"measured {whole}"
    assert broken == pytest.approx(2 * math.pi * R * R, rel=REL), f"measured {broken}"


def packed_stones(seed=0, overlap=0.01):
    """A 5 x 4 grid of hexagonal 7-ball stones, randomly turned, neighbours overlapping
    by ``overlap`` R along the grid lines (a jammed-like packing with real contacts)."""
    rng = np.random.default_rng(seed)
    base, rad0, bi0, bj0 = hex_stone(2)
    pitch = 6 * R * (1 - overlap / 6)            # hexagon extent 6R along x through two balls
    pos, rad, bi, bj = [], [], [], []
    for gx in range(5):
        for gy in range(4):
            th = rng.choice([0.0, np.pi / 3]) + rng.normal(0, 0.01)
            c, s = np.cos(th), np.sin(th)
            p = base @ np.array([[c, s], [-s, c]]) + [0.04 + gx * pitch, 0.04 + gy * pitch]
            bi.append(bi0 + len(pos) * 7)
            bj.append(bj0 + len(pos) * 7)
            pos.append(p)
            rad.append(rad0)
    return np.vstack(pos), np.concatenate(rad), np.concatenate(bi), np.concatenate(bj)


def test_fast_areas_match_the_full_union():
    """Sum of solids minus inter-stone lenses (and the analytic disks) against the shapely
    union of everything clipped to the region, with the plate level cutting a row."""
    import shapely
    pos, rad, bi, bj = packed_stones()
    intact = np.ones(len(bi), bool)
    box = (0.0, 0.4, 0.0, 0.04 + 3.2 * 6 * R)       # the top row crosses the plate level
    n, lab = fragments(len(rad), bi, bj, intact)
    out = void_ratio(pos, rad, lab, n, bi, bj, intact, *box)
    region = shapely.box(box[0], box[2], box[1], box[3])
    solids = [stone_solid(pos[lab == f], rad[lab == f], *_local_bonds(lab, f, bi, bj)) for f in range(n)]
    ref_solid = shapely.intersection(shapely.union_all(solids), region).area
    disks = shapely.buffer(shapely.points(pos), rad, quad_segs=64)
    ref_balls = shapely.intersection(shapely.union_all(disks), region).area
    assert out["area_solid"] == pytest.approx(ref_solid, rel=1e-3)
    assert (1 - out["void_ratio_balls"]) * region.area == pytest.approx(ref_balls, rel=1e-3)


def _local_bonds(lab, f, bi, bj):
    ids = np.nonzero(lab == f)[0]
    loc = {g: k for k, g in enumerate(ids)}
    keep = (lab[bi] == f) & (lab[bj] == f)
    return np.array([loc[g] for g in bi[keep]]), np.array([loc[g] for g in bj[keep]])


def test_cache_reuses_rigid_stones_and_rebuilds_deformed_ones():
    from ballaststudy.metrics.void_ratio import SolidCache
    pos, rad, bi, bj = packed_stones(overlap=0.0)
    intact = np.ones(len(bi), bool)
    box = (-1.0, 1.0, -1.0, 1.0)
    n, lab = fragments(len(rad), bi, bj, intact)
    cache = SolidCache(tolerance=1e-6)
    first = void_ratio(pos, rad, lab, n, bi, bj, intact, *box, cache=cache)
    assert cache.builds == n and cache.hits == 0
    th = 0.3                                     # the whole packing turned and shifted
    rot = np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]])
    moved = pos @ rot + [0.01, -0.02]
    again = void_ratio(moved, rad, lab, n, bi, bj, intact, *box, cache=cache)
    assert cache.hits == n and cache.builds == n
    assert again["area_solid"] == pytest.approx(first["area_solid"], rel=1e-12)
    bent = moved.copy()
    bent[lab == 0] += np.random.default_rng(1).normal(0, 1e-4, (7, 2))   # one stone deformed
    void_ratio(bent, rad, lab, n, bi, bj, intact, *box, cache=cache)
    assert cache.builds == n + 1



def test_cache_moves_the_solid_of_a_stone_cut_by_the_plate_level():
    """A stone crossing the plate level is cut from its kept polygon moved by the fitted
    rigid motion: the same areas as solids built anew, within the polygons' round-off."""
    from ballaststudy.metrics.void_ratio import SolidCache
    pos, rad, bi, bj = packed_stones(overlap=0.0)
    intact = np.ones(len(bi), bool)
    n, lab = fragments(len(rad), bi, bj, intact)
    top = float(np.median(pos[:, 1]))           # cuts a row of stones
    box = (-1.0, 1.0, -1.0, top)
    cache = SolidCache(tolerance=1e-6)
    void_ratio(pos, rad, lab, n, bi, bj, intact, *box, cache=cache)
    built = cache.builds                        # the stones below or across the level
    th = 0.02                                   # the packing turned a little and lowered
    rot = np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]])
    moved = (pos - pos.mean(0)) @ rot + pos.mean(0) + [0.003, -0.004]
    reused = void_ratio(moved, rad, lab, n, bi, bj, intact, *box, cache=cache)
    assert 0 < built < n and cache.hits == built      # every stone seen before: reused
    fresh = void_ratio(moved, rad, lab, n, bi, bj, intact, *box)
    cut = void_ratio(moved, rad, lab, n, bi, bj, intact, -1.0, 1.0, -1.0, 1.0)
    assert fresh["area_solid"] < 0.9 * cut["area_solid"]     # the level cuts stones indeed
    assert reused["area_solid"] == pytest.approx(fresh["area_solid"], rel=1e-9)

def test_lens_and_cut_disk_against_polygons():
    import shapely
    from ballaststudy.metrics.void_ratio import _disk_area_below, _lens
    a, b = shapely.Point(0, 0).buffer(1.0, 256), shapely.Point(1.3, 0).buffer(0.7, 256)
    assert _lens(np.array(1.3), 1.0, 0.7) == pytest.approx(a.intersection(b).area, rel=1e-4)
    assert _lens(np.array(0.1), 1.0, 0.7) == pytest.approx(np.pi * 0.49)
    cut = a.intersection(shapely.box(-2, -2, 2, 0.4)).area
    assert _disk_area_below(np.array(0.0), 1.0, 0.4) == pytest.approx(cut, rel=1e-4)
    assert _disk_area_below(np.array(5.0), 1.0, 0.4) == 0.0
