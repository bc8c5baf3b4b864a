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


def test_pore_enclosed_by_several_stones_stays_void():
    # four separate bars (no bonds between them) framing a square pore; at each corner the
    # end balls of two bars coincide, so the frame is closed and the pore a hole of the union
    row = lambda x0, y0, dx, dy: [(x0 + i * dx, y0 + i * dy) for i in range(9)]
    parts = [row(0, 0, 2 * R, 0), row(0, 16 * R, 2 * R, 0), row(0, 0, 0, 2 * R), row(16 * R, 0, 0, 2 * R)]
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
    stadium = 4 * R * R * 8 + math.pi * R * R
    corner = R * R * (1 + 3 * math.pi / 4)       # overlap of two stadia sharing an end disk
    expected = 4 * stadium - 4 * corner           # the 14R x 14R pore stays void
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
