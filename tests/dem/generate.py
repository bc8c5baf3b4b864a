"""Seeded initial arrangements (one integer seed -> bitwise identical arrays)."""
import numpy as np


def random_disks(n, x0, x1, y0, rmin, rmax, seed, vmax=0.0):
    """n disks, radii uniform in [rmin, rmax], on a jittered square lattice of spacing
    2.1 rmax filling the width [x0, x1] upward from y0 (never overlapping), with random
    velocities in [-vmax, vmax]. Returns x, y, r, vx, vy."""
    rng = np.random.default_rng(seed)
    s = 2.1 * rmax
    ncol = max(1, int((x1 - x0) / s))
    k = np.arange(n)
    r = rng.uniform(rmin, rmax, n)
    jitter = rng.uniform(-1.0, 1.0, (n, 2)) * (0.5 * s - r)[:, None]
    x = x0 + (k % ncol + 0.5) * s + jitter[:, 0]
    y = y0 + (k // ncol + 0.5) * s + jitter[:, 1]
    v = rng.uniform(-vmax, vmax, (n, 2))
    return x, y, r, v[:, 0], v[:, 1]
