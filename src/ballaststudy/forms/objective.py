"""Objective of a form database (thesis 3.3): target mass per size group and per shape flag.

A database definition (config/databases.yaml) gives total mass, grading, FI, SI, LI and the
materials. The objective splits the mass into size groups d/D from the grading; inside each
group SI (and FI, when given) apply as mass fractions, and the long-stone mass (LI) goes to
the largest groups that can hold stones >= 100 mm.
"""

from dataclasses import dataclass, field

import numpy as np

from ..standards import (
    LONG_STONE_LENGTH_MM, NON_CUBIC_RATIO, SIZE_GROUP_BOUNDS_MM, category_target, grading_target,
)


class ObjectiveError(ValueError):
    """A database definition that cannot be generated; `key` names the offending entry."""

    def __init__(self, key, message):
        super().__init__(message)
        self.key = key


@dataclass(frozen=True)
class Material:
    name: str
    mass_fraction: float
    density_kg_m3: float


@dataclass(frozen=True)
class FormParams:
    """How stones are drawn (thesis 3.1); see config/config.yaml for the reasons of the defaults."""
    n_vertices: int = 20          # random points on the ellipsoid surface = polyhedron vertices
    ab_ratio_max: float = 2.5     # largest a/b of a drawn target form
    cb_ratio_min: float = 0.3     # smallest c/b of a drawn target form
    batch: int = 64               # candidates evaluated together (vectorised)


@dataclass
class GroupObjective:
    """Objective masses (kg) of one size group d <= b < D (lengths in m)."""
    index: int
    lower: float
    upper: float
    mass: float
    non_cubic: float
    flat: float | None
    long: float

    @property
    def name(self):
        return f"{self.lower * 1e3:g}/{self.upper * 1e3:g}"


@dataclass
class Objective:
    """Everything the generator aims at for one database."""
    name: str
    total_mass: float
    percent_passing: tuple
    flakiness_index: float | None
    shape_index: float
    particle_length_index: float
    materials: tuple
    groups: list = field(default_factory=list)


def _check_grading(pp):
    pp = np.asarray(pp, dtype=float)
    for i, v in enumerate(pp):
        if not 0.0 <= v <= 100.0:
            raise ObjectiveError(f"grading[{i}]", f"percent passing {v:g} is outside the allowed range 0-100")
    bad = np.nonzero(np.diff(pp) > 0)[0]
    if bad.size:
        i = bad[0] + 1
        raise ObjectiveError(f"grading[{i}]", f"percent passing rises from {pp[i - 1]:g} to {pp[i]:g} "
                             "towards a smaller sieve; it must not increase as the sieve size decreases")


def _target(prefix, key, value):
    try:
        t = category_target(prefix, value)
    except ValueError as err:
        raise ObjectiveError(key, str(err)) from None
    if not 0.0 <= t <= 100.0:
        raise ObjectiveError(key, f"{t:g} % is outside the allowed range 0-100")
    return t


def _allocate_long(group_mass, uppers_mm, long_total, params):
    """Long-stone mass per group, largest groups first, only where a >= 100 mm is reachable."""
    long = np.zeros_like(group_mass)
    left = long_total
    reach_mm = 0.98 * params.ab_ratio_max   # a reaches ab_ratio_max*b with b just below D
    for k in np.argsort(-uppers_mm):
        if left <= 0:
            break
        if uppers_mm[k] * reach_mm > LONG_STONE_LENGTH_MM * 1.02:
            long[k] = min(left, group_mass[k])
            left -= long[k]
    if left > 1e-9 * max(long_total, 1.0):
        raise ObjectiveError("particle_length_index", (
            f"{100 * left / group_mass.sum():.3g} % of the mass cannot be long stones: only groups with "
            f"D > {LONG_STONE_LENGTH_MM / (0.98 * params.ab_ratio_max):.3g} mm can hold a >= 100 mm "
            f"at a/b <= {params.ab_ratio_max:g}; lower particle_length_index or use a coarser grading"))
    return long


def _check_shapes_reachable(si, fi, params):
    """Non-cubic needs a/c > 3 and flat needs c < slot (about D/2, b >= d = D/1.25 .. D/2)
    inside the drawn bounds a/b <= ab_ratio_max, c/b >= cb_ratio_min (generator margins 6 %)."""
    if si > 0 and params.ab_ratio_max / params.cb_ratio_min <= NON_CUBIC_RATIO * 1.1:
        raise ObjectiveError("shape_index", (
            f"SI {si:g} % cannot be met: a/c reaches at most {params.ab_ratio_max / params.cb_ratio_min:.3g} "
            f"with forms.ab_ratio_max {params.ab_ratio_max:g} and forms.cb_ratio_min {params.cb_ratio_min:g}, "
            f"non-cubic needs a/c > {NON_CUBIC_RATIO:g}"))
    if fi is not None and fi > 0 and params.cb_ratio_min >= 0.6:
        raise ObjectiveError("flakiness_index", (
            f"FI {fi:g} % cannot be met: flat stones need c below about half the upper sieve, "
            f"but forms.cb_ratio_min is {params.cb_ratio_min:g} (must be < 0.6 for FI > 0)"))


def build_objective(name, definition, params=FormParams()):
    """Objective from one parsed database definition (a dict as in databases.yaml).

    Raises ObjectiveError naming the key for a value outside its range, an unknown category,
    SI > FI, or a target no stone can meet.
    """
    mass = float(definition["mass_kg"])
    if not mass > 0:
        raise ObjectiveError("mass_kg", f"{mass:g} kg; the total mass must be > 0")
    try:
        pp = grading_target(definition["grading"])
    except ValueError as err:
        raise ObjectiveError("grading", str(err)) from None
    _check_grading(pp)
    si = _target("SI_RB", "shape_index", definition["shape_index"])
    li = _target("L_RB", "particle_length_index", definition["particle_length_index"])
    fi_value = definition.get("flakiness_index")
    fi = None if fi_value is None else _target("FI_RB", "flakiness_index", fi_value)
    if fi is not None and si > fi:
        raise ObjectiveError("shape_index", f"SI {si:g} % exceeds FI {fi:g} %: a non-cubic stone "
                             "(a/c > 3) is stricter than a flat one, so SI <= FI (thesis 3.3)")
    _check_shapes_reachable(si, fi, params)
    materials = tuple(Material(n, float(m["mass_fraction"]), float(m["density_kg_m3"]))
                      for n, m in definition["materials"].items())
    fractions = sum(m.mass_fraction for m in materials)
    if abs(fractions - 1.0) > 1e-6:
        raise ObjectiveError("materials", f"mass fractions sum to {fractions:g}; they must sum to 1")

    bounds = np.asarray(SIZE_GROUP_BOUNDS_MM)
    passing = np.concatenate([[100.0], pp, [0.0]])   # 100 % pass 100 mm, none passes 4 mm
    group_mass = mass * (passing[:-1] - passing[1:]) / 100.0
    long = _allocate_long(group_mass, bounds[:-1], mass * li / 100.0, params)
    groups = [GroupObjective(k, bounds[k + 1] * 1e-3, bounds[k] * 1e-3, group_mass[k],
                             group_mass[k] * si / 100.0,
                             None if fi is None else group_mass[k] * fi / 100.0, long[k])
              for k in range(len(group_mass)) if group_mass[k] > 0]
    return Objective(name, mass, pp, fi, si, li, materials, groups)
