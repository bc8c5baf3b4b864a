import numpy as np

from ballaststudy.metrics import fragment_centroids, fragments


def test_chain_splits_when_a_bond_breaks():
    bi, bj = np.array([0, 1, 2]), np.array([1, 2, 3])
    n, lab = fragments(5, bi, bj, np.array([True, True, True]))
    assert n == 2, f"intact chain + lone ball: measured {n} fragments, expected 2"
    assert list(lab) == [0, 0, 0, 0, 1], f"labels {lab}"
    n, lab = fragments(5, bi, bj, np.array([True, False, True]))
    assert n == 3, f"broken middle bond: measured {n} fragments, expected 3"
    assert list(lab) == [0, 0, 1, 1, 2], f"labels {lab}"


def test_triangle_survives_one_broken_bond():
    bi, bj = np.array([0, 1, 0]), np.array([1, 2, 2])
    n, lab = fragments(3, bi, bj, np.array([False, True, True]))
    assert n == 1, f"triangle with one broken bond: measured {n} fragments, expected 1"


def test_non_ballast_balls_are_not_fragments():
    bi, bj = np.array([0, 2]), np.array([1, 3])
    ballast = np.array([True, True, False, False, True])
    n, lab = fragments(5, bi, bj, np.array([True, True]), ballast)
    assert n == 2, f"measured {n}, expected 2 (stone 0-1, lone ball 4)"
    assert list(lab) == [0, 0, -1, -1, 1], f"labels {lab}"


def test_centroid_is_area_weighted():
    pos = np.array([[0.0, 0.0], [3.0, 0.0], [10.0, 5.0]])
    rad = np.array([1.0, 2.0, 1.0])
    c = fragment_centroids(np.array([0, 0, 1]), 2, pos, rad)
    assert np.allclose(c[0], [3.0 * 4 / 5, 0.0]), f"measured {c[0]}, expected [2.4, 0]"
    assert np.allclose(c[1], [10.0, 5.0])
