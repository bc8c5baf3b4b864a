"""Fragments: the stones as they are now, i.e. connected groups of balls held together by
bonds with at least one intact flat-joint element (physics spec "Fragments and stones"; a
broken stone becomes two or more fragments). The one definition, a pure function of plain
arrays: Simulation.fragments, the rigs and the metrics all use it."""
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components


def fragments(n_balls, bond_i, bond_j, bond_intact, ballast=None):
    """Label every ball with its fragment.

    n_balls: number of balls (ids 0 .. n_balls-1).
    bond_i, bond_j: (m,) ball ids of each flat-joint bond.
    bond_intact: (m,) bool, True if the bond has at least one intact element
        (engine: ``bonds.active & bonds.state.any(axis=1)``).
    ballast: optional (n_balls,) bool; False for balls that are not ballast (plate
        pebbles, the loading ball, deleted balls). They get label -1 and are not counted.

    Returns (n_fragments, labels) with labels (n_balls,) int in 0..n_fragments-1 (or -1),
    numbered in order of the lowest ball id of each fragment.
    """
    n = int(n_balls)
    bi = np.asarray(bond_i, dtype=np.int64)
    bj = np.asarray(bond_j, dtype=np.int64)
    keep = np.asarray(bond_intact, dtype=bool)
    mask = np.ones(n, bool) if ballast is None else np.asarray(ballast, dtype=bool)
    if mask.shape != (n,):
        raise ValueError(f"ballast mask has shape {mask.shape}, expected ({n},)")
    keep = keep & mask[bi] & mask[bj]
    graph = coo_matrix((np.ones(int(keep.sum())), (bi[keep], bj[keep])), shape=(n, n))
    _, raw = connected_components(graph, directed=False)
    labels = np.full(n, -1, dtype=np.int64)
    if mask.any():
        # renumber the components that contain ballast balls: 0, 1, ... by lowest ball id
        uniq, first = np.unique(raw[mask], return_index=True)
        order = np.argsort(first)
        remap = np.empty(uniq.size, dtype=np.int64)
        remap[order] = np.arange(uniq.size)
        labels[mask] = remap[np.searchsorted(uniq, raw[mask])]
    return int(labels.max() + 1), labels
