"""Fragments (defined in dem.fragments) and their centroids: pure functions of plain arrays."""
import numpy as np

from ..dem.fragments import fragments  # noqa: F401  (one definition, used by metrics.cycle)


def fragment_centroids(labels, n_fragments, pos, rad):
    """Area-weighted centroid (x, y) [m] of each fragment's disks, shape (n_fragments, 2)."""
    ok = labels >= 0
    w = np.pi * np.asarray(rad, float)[ok] ** 2
    lab = labels[ok]
    p = np.asarray(pos, float)[ok]
    a = np.bincount(lab, weights=w, minlength=n_fragments)
    cx = np.bincount(lab, weights=w * p[:, 0], minlength=n_fragments)
    cy = np.bincount(lab, weights=w * p[:, 1], minlength=n_fragments)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.column_stack([cx / a, cy / a])
