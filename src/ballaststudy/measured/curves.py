"""One measured curve file: N (load cycles) against a value, two numbers a line.

Digitised curves come with rows out of order and, now and then, a point read twice; the
reader sorts by N and accepts repeats of the same point, but a file that is still not a
function of N (two different values at one N), a negative cycle or a strain beyond 1 is
rejected with one line naming the file and the line.
"""
import re

import numpy as np

from ..schema import ConfigError

_SPLIT = re.compile(r"[,;\s]+")
TO_SI = {"1": 1.0, "%": 0.01, "m": 1.0, "mm": 1e-3}
STRAINS = ("axial_strain", "volumetric_strain")


def read_pairs(path):
    """(N, value, line numbers) as read, blank and '#' lines skipped."""
    n, v, lines = [], [], []
    with open(path) as f:
        for k, text in enumerate(f, start=1):
            s = text.strip()
            if not s or s.startswith("#"):
                continue
            parts = [p for p in _SPLIT.split(s) if p]
            try:
                a, b = (float(p) for p in parts)
            except ValueError:
                raise ConfigError(f"{path}:{k}", None,
                                  f"expected two numbers 'N, value', got {s!r}") from None
            if not (np.isfinite(a) and np.isfinite(b)):
                raise ConfigError(f"{path}:{k}", None, f"not a finite number: {s!r}")
            n.append(a)
            v.append(b)
            lines.append(k)
    if not n:
        raise ConfigError(path, None, "no data lines")
    return np.array(n), np.array(v), np.array(lines)


def read_curve(path, quantity, units, sign):
    """The curve in SI units, compression positive, sorted by N: (N, value)."""
    n, v, lines = read_pairs(path)
    bad = np.nonzero(n < 0)[0]
    if bad.size:
        k = bad[0]
        raise ConfigError(f"{path}:{lines[k]}", None, f"negative cycle number {n[k]:g}")
    v = v * TO_SI[units] * (-1.0 if sign == "dilation_positive" else 1.0)
    if quantity in STRAINS:
        bad = np.nonzero(np.abs(v) > 1.0)[0]
        if bad.size:
            k = bad[0]
            raise ConfigError(f"{path}:{lines[k]}", None,
                              f"|strain| = {abs(v[k]):g} > 1 (units {units!r}: a fraction is "
                              f"'1', percent is '%')")
    order = np.argsort(n, kind="stable")
    n, v, lines = n[order], v[order], lines[order]
    same = np.nonzero(np.diff(n) == 0)[0]
    clash = same[v[same] != v[same + 1]]
    if clash.size:
        k = clash[0]
        raise ConfigError(f"{path}:{lines[k]}", None,
                          f"not a function of N: line {lines[k + 1]} gives another value at "
                          f"N = {n[k]:g} ({v[k]:g} vs {v[k + 1]:g})")
    keep = np.r_[True, np.diff(n) != 0]
    return n[keep], v[keep]
