import numpy as np

from ballaststudy.metrics import (coordination_numbers, fragments, ghost_particles, in_shoulder,
                                  touching_container)

# stones: A = balls 0,1 (bonded), B = 2, C = 3, D = 4, E = 5 (touches the container),
# F = 6 (shoulder); ball 7 is a plate pebble (not ballast)
BALLAST = np.array([True] * 7 + [False])
BOND_I, BOND_J = np.array([0]), np.array([1])
CI = np.array([0, 0, 1, 1, 0, 2, 3, 4, 0, 6])
CJ = np.array([1, 2, 2, 3, 4, 3, 4, 5, 7, 5])
FN = np.array([100, 50, 30, 10, 0, 5, 20, 1, 200, 3], float)
# A-A internal, A-B twice, A-C, A-D without force, B-C, C-D, D-E, A-plate, F-E


def labels(intact=True):
    return fragments(8, BOND_I, BOND_J, np.array([intact]), BALLAST)


def test_coordination_counts_distinct_neighbour_stones():
    n, lab = labels()
    assert n == 6 and list(lab) == [0, 0, 1, 2, 3, 4, 5, -1], lab
    cn = coordination_numbers(lab, n, CI, CJ, FN)
    expected = [3, 2, 3, 2, 2, 1]          # A: B, C, plate; B: A, C; C: A, B, D; D: C, E; E: D, F; F: E
    assert list(cn) == expected, f"measured {cn}, expected {expected}"
    assert cn.mean() == 13 / 6
    cn = coordination_numbers(lab, n, CI, CJ, FN, count_plate_contact=False)
    assert list(cn) == [2, 2, 3, 2, 2, 1], f"without plate: measured {cn}"


def test_ghosts_exclude_container_and_shoulder():
    n, lab = labels()
    cn = coordination_numbers(lab, n, CI, CJ, FN)
    wall = touching_container(lab, n, ball_touches_container=np.arange(8) == 5)
    assert list(wall) == [False, False, False, False, True, False]
    shoulder = np.array([False] * 5 + [True])
    g = ghost_particles(cn, wall | shoulder)
    assert list(np.nonzero(g)[0]) == [1, 3], f"ghosts measured {np.nonzero(g)[0]}, expected B, D = [1, 3]"
    assert ghost_particles(cn, np.zeros(n, bool)).sum() == 4
    g = ghost_particles(coordination_numbers(lab, n, CI, CJ, FN, count_plate_contact=False), wall | shoulder)
    assert g.sum() == 3, "without the plate A becomes a ghost too"


def test_broken_bond_makes_internal_contact_count():
    n, lab = labels(intact=False)
    assert n == 7
    cn = coordination_numbers(lab, n, CI, CJ, FN)
    # A0 (ball 0): A1, B, plate; A1 (ball 1): A0, B, C
    assert list(cn[:2]) == [3, 3], f"measured {cn[:2]}, expected [3, 3]"


def test_geometric_container_contact_and_shoulder():
    pos = np.array([[0.0105, 0.1], [0.1, 0.0108], [0.1, 0.1], [0.3395, 0.1]])
    rad = np.full(4, 0.01)
    lab = np.arange(4)
    t = touching_container(lab, 4, pos, rad, 0.0, 0.34, 0.0, tolerance=1e-3)
    assert list(t) == [True, True, False, True], t
    t = touching_container(lab, 4, pos, rad, 0.0, 0.34, 0.0, tolerance=0.0)
    assert list(t) == [False, False, False, True], t
    # plate: middle 0.17, half width 0.05, bottom at 0.18; shoulder depth 0.02
    c = np.array([[0.05, 0.17], [0.05, 0.15], [0.17, 0.19], [0.30, 0.2]])
    s = in_shoulder(c, 0.17, 0.05, 0.18, 0.02)
    assert list(s) == [True, False, False, True], s


def test_container_flags_from_engine_contact_list():
    from ballaststudy.metrics import container_flags_from_contacts
    # wall contacts j = -1 - segment; segments 0..2 are container, 5 is the plate's
    ci = np.array([0, 1, 2, 3])
    cj = np.array([-1, -6, 3, -3])       # ball0-seg0, ball1-seg5, ball2-ball3, ball3-seg2
    f = container_flags_from_contacts(5, ci, cj, [0, 1, 2])
    assert list(f) == [True, False, False, True, False], f
