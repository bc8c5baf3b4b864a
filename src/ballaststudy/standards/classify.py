"""Classification of an aggregate the way a lab reports it (EN 13450 / EN 933, thesis 2.1, 3.2).

Inputs are per-stone dimensions a >= b >= c in metres and masses in kg (SI inside); sieve
sizes are in mm because the standard names them so.
"""

from dataclasses import dataclass, field

import numpy as np

from .en13450 import (
    FI_CATEGORIES, GRADING_CATEGORIES, GRADING_SIEVES_MM, GRID_SIEVES, LI_CATEGORIES,
    LONG_STONE_LENGTH_MM, NON_CUBIC_RATIO, SI_CATEGORIES, SIZE_GROUP_BOUNDS_MM,
)

_GRID_D = np.array([g[0] for g in GRID_SIEVES])
_GRID_UPPER = np.array([g[1] for g in GRID_SIEVES])
_GRID_SLOT = np.array([g[2] for g in GRID_SIEVES])


def slot_widths_m(b):
    """Grid-sieve slot width (m) for each stone's EN 933-3 group from b; NaN outside 4-100 mm."""
    b_mm = np.atleast_1d(np.asarray(b, dtype=float)) * 1e3
    inside = (b_mm[:, None] >= _GRID_D[None, :]) & (b_mm[:, None] < _GRID_UPPER[None, :])
    slot = np.where(inside, _GRID_SLOT[None, :], 0.0).sum(axis=1)
    return np.where(inside.any(axis=1), slot * 1e-3, np.nan)


def stone_flags(a, b, c):
    """(flat, non_cubic, long) boolean arrays (thesis 3.2.2).

    flat: c < slot width of the stone's grid sieve (passes the bar sieve);
    non-cubic: a/c > 3; long: a >= 100 mm.
    """
    a, b, c = (np.atleast_1d(np.asarray(x, dtype=float)) for x in (a, b, c))
    slot = slot_widths_m(b)
    flat = np.where(np.isnan(slot), False, c < np.nan_to_num(slot))
    non_cubic = a > NON_CUBIC_RATIO * c
    long = a * 1e3 >= LONG_STONE_LENGTH_MM
    return flat, non_cubic, long


def sieve_group(b):
    """Index k of the size group d_k <= b < D_k (eq. 3.1), D_k = SIZE_GROUP_BOUNDS_MM[k],
    d_k = SIZE_GROUP_BOUNDS_MM[k+1]; -1 where b lies outside 4-100 mm."""
    b_mm = np.atleast_1d(np.asarray(b, dtype=float)) * 1e3
    asc = np.asarray(SIZE_GROUP_BOUNDS_MM, dtype=float)[::-1]
    k = len(asc) - 1 - np.searchsorted(asc, b_mm, side="right")
    return np.where((b_mm >= asc[0]) & (b_mm < asc[-1]), k, -1)


def percent_passing(b, mass, sieves_mm=GRADING_SIEVES_MM):
    """Percent by mass passing each sieve: a stone passes a square mesh D iff b < D (3.2.1)."""
    b_mm = np.atleast_1d(np.asarray(b, dtype=float)) * 1e3
    mass = np.atleast_1d(np.asarray(mass, dtype=float))
    total = mass.sum()
    return np.array([100.0 * mass[b_mm < s].sum() / total for s in sieves_mm])


def size_diversity(passing):
    """Size diversity SD = sum_i |f(i) - 50| over the grading sieves (thesis eq. 3.3)."""
    return float(np.sum(np.abs(np.asarray(passing, dtype=float) - 50.0)))


def grading_categories_met(passing, sieves_mm=GRADING_SIEVES_MM):
    """Names of the G_CRB categories whose every specified range contains the curve."""
    pp = dict(zip(sieves_mm, passing))
    return [name for name, ranges in GRADING_CATEGORIES.items()
            if all(s in pp and lo - 1e-9 <= pp[s] <= hi + 1e-9 for s, (lo, hi) in ranges.items())]


def _categories_met(value, table):
    return [name for name, (lo, hi) in table.items() if lo - 1e-9 <= value <= hi + 1e-9]


@dataclass
class Classification:
    """What a lab report would state about an aggregate."""
    sieves_mm: tuple
    percent_passing: np.ndarray
    grading_categories: list
    flakiness_index: float
    shape_index: float
    particle_length_index: float
    fi_categories: list = field(default_factory=list)
    si_categories: list = field(default_factory=list)
    li_categories: list = field(default_factory=list)
    size_diversity: float = 0.0
    total_mass: float = 0.0
    particle_count: int = 0


def classify_aggregate(a, b, c, mass, sieves_mm=GRADING_SIEVES_MM):
    """Classify an aggregate from per-stone a >= b >= c (m) and mass (kg)."""
    mass = np.atleast_1d(np.asarray(mass, dtype=float))
    flat, non_cubic, long = stone_flags(a, b, c)
    total = mass.sum()
    fi = 100.0 * mass[flat].sum() / total
    si = 100.0 * mass[non_cubic].sum() / total
    li = 100.0 * mass[long].sum() / total
    pp = percent_passing(b, mass, sieves_mm)
    return Classification(
        sieves_mm=tuple(sieves_mm), percent_passing=pp,
        grading_categories=grading_categories_met(pp, sieves_mm),
        flakiness_index=fi, shape_index=si, particle_length_index=li,
        fi_categories=_categories_met(fi, FI_CATEGORIES),
        si_categories=_categories_met(si, SI_CATEGORIES),
        li_categories=_categories_met(li, LI_CATEGORIES),
        size_diversity=size_diversity(pp) if tuple(sieves_mm) == GRADING_SIEVES_MM else float("nan"),
        total_mass=float(total), particle_count=int(mass.size),
    )
