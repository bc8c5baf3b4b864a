"""The ballast random form generator (thesis 3.1-3.3) filling a database objective.

Each stone: an ellipsoid with drawn axes, n random surface points, their convex hull.
Axes are drawn so the evaluated form (a, b, c, thesis 3.2) lands in the objective group
(size group x non-cubic x long [x flat]) whose mass is most lacking; the ellipsoid-to-form
shrink and the volume factor V/(abc) are learned on the fly. Unlike the thesis, a group is
not simply filled until its last stone overshoots: once the missing mass is about one stone,
the stone is drawn for that mass and the closest candidate is taken only if it brings the
group nearer its objective.
"""

import itertools
from dataclasses import dataclass

import numpy as np

from ..standards import LONG_STONE_LENGTH_MM, NON_CUBIC_RATIO
from ..standards.classify import sieve_group, slot_widths_m, stone_flags
from . import geometry
from .objective import FormParams, Objective, ObjectiveError

_MARGIN = 0.03          # targets keep this relative distance from every class boundary
_MAX_BATCHES = 20000    # per database; far above what any feasible objective needs
# weights of the missing masses when a last stone is weighed: 1/tolerance^2 of the targets
# (grading and SI within 1 pp, LI within 0.5 pp), so LI counts four times
_WEIGHT = {"long": 4.0}


class GenerationError(RuntimeError):
    """The objective cannot be met by drawn stones (reported with the group and class)."""


@dataclass
class Stone:
    vertices: np.ndarray
    faces: np.ndarray
    a: float
    b: float
    c: float
    dir_a: np.ndarray
    dir_b: np.ndarray
    volume: float
    centroid: np.ndarray
    mass: float
    material: int
    group: int
    flat: bool
    non_cubic: bool
    long: bool


class _Ledger:
    """Missing mass of one size group: in total and on each side of each shape flag."""

    def __init__(self, g):
        self.total = g.mass
        self.sides = {"non_cubic": {True: g.non_cubic, False: g.mass - g.non_cubic},
                      "long": {True: g.long, False: g.mass - g.long}}
        if g.flat is not None:
            self.sides["flat"] = {True: g.flat, False: g.mass - g.flat}
        self.closed = set()     # (flag, value) sides given up: no stone fits what they lack

    def _lacking(self, name, value):
        return self.sides[name][value] > 0 and (name, value) not in self.closed

    def combos(self):
        """All flag combinations, best first: those whose every side still lacks mass, then
        those touching the fewest given-up sides; among equals the most-lacking (sum of the
        missing masses of the chosen sides)."""
        names = list(self.sides)
        scored = []
        for values in itertools.product((True, False), repeat=len(names)):
            flags = dict(zip(names, values))
            lacking = all(self._lacking(n, v) for n, v in flags.items())
            n_closed = sum((n, v) in self.closed for n, v in flags.items())
            missing = sum(self.sides[n][v] for n, v in flags.items())
            scored.append(((not lacking, n_closed, -missing), flags))
        return [f for _, f in sorted(scored, key=lambda t: t[0])]

    def _open_sides(self, flags):
        return {n: self.sides[n][v] for n, v in flags.items() if self._lacking(n, v)}

    def cap(self, flags):
        """The mass the next stone of class `flags` may have without overfilling a side."""
        return min([self.total, *(m for n, v in flags.items() if (m := self.sides[n][v]) > 0)])

    def gain(self, stone):
        """How much taking the stone reduces the weighted sum of squared missing masses (group
        total and the stone's side of every flag): > 0 means the group nears its objective."""
        missing = [(1.0, self.total)] + [(_WEIGHT.get(n, 1.0), side[bool(getattr(stone, n))])
                                         for n, side in self.sides.items()]
        return sum(w * (r * r - (r - stone.mass) ** 2) for w, r in missing)

    def book(self, stone):
        self.total -= stone.mass
        for n, side in self.sides.items():
            side[bool(getattr(stone, n))] -= stone.mass

    def close_binding_side(self, flags):
        """No stone fits the smallest missing mass: give that side up (leave its error).
        Returns False when the binding limit is the group total itself."""
        open_sides = self._open_sides(flags)
        if not open_sides or min(open_sides.values()) >= self.total:
            return False
        name = min(open_sides, key=open_sides.get)
        self.closed.add((name, flags[name]))
        return True


class FormGenerator:
    """Generates the stones of one database objective, deterministically from `seed`."""

    def __init__(self, objective: Objective, seed: int, params: FormParams = FormParams()):
        self.objective = objective
        self.params = params
        self.rng = np.random.default_rng(seed)
        self.stones = []
        self._material_mass = np.zeros(len(objective.materials))
        self._density = np.array([m.density_kg_m3 for m in objective.materials])
        self._fraction = np.array([m.mass_fraction for m in objective.materials])
        self._batches = 0
        self._drawable_cache = {}
        self._calibrate()

    # -- learning the ellipsoid -> form relation -------------------------------------------
    def _calibrate(self):
        """Initial shrink (form dimension / ellipsoid axis) and volume factor V/(abc)."""
        axes = self.rng.uniform(0.5, 1.0, size=(128, 3)) * np.array([1.0, 0.7, 0.45])
        pts = geometry.ellipsoid_surface_points(self.rng, axes, self.params.n_vertices)
        a, b, c, _, _ = geometry.evaluate_dimensions(pts)
        self.shrink = np.median(np.column_stack([a, b, c]) / (2 * axes), axis=0)
        vols = [geometry.volume_and_centroid(*geometry.convex_hull(p))[0] for p in pts[:32]]
        self.volume_factor = float(np.median(np.array(vols) / (a * b * c)[:32]))

    def _learn(self, dims, semi_axes, volume_factors):
        self.shrink = 0.9 * self.shrink + 0.1 * np.median(dims / (2 * semi_axes), axis=0)
        if volume_factors:
            self.volume_factor = 0.9 * self.volume_factor + 0.1 * float(np.median(volume_factors))

    # -- targets --------------------------------------------------------------------------
    def _fits(self, a, b, c, group, flags, margin):
        """Whether target dimensions sit inside the class with a relative margin."""
        lo, hi = group.lower * (1 + margin), group.upper * (1 - margin)
        ok = (b >= lo) & (b <= hi) & (c <= b) & (a >= b)
        ok &= (c >= self.params.cb_ratio_min * b * (1 - 1e-9)) & (a <= self.params.ab_ratio_max * b * (1 + 1e-9))
        ratio = a / c
        ok &= ratio > NON_CUBIC_RATIO * (1 + margin) if flags["non_cubic"] else ratio < NON_CUBIC_RATIO * (1 - margin)
        a_mm = a * 1e3
        ok &= a_mm > LONG_STONE_LENGTH_MM * (1 + margin) if flags["long"] else a_mm < LONG_STONE_LENGTH_MM * (1 - margin)
        if "flat" in flags:
            slot = slot_widths_m(b)
            ok &= ~np.isnan(slot)
            s = np.nan_to_num(slot)
            ok &= c < s * (1 - margin) if flags["flat"] else c > s * (1 + margin)
        return ok

    def _draw_targets(self, group, flags, n):
        """n target (a, b, c) drawn uniformly inside the class bounds; invalid rows dropped."""
        p, r = self.params, self.rng
        b = r.uniform(group.lower, group.upper, n)
        c_lo, c_hi = p.cb_ratio_min * b, b.copy()
        if "flat" in flags:
            slot = np.nan_to_num(slot_widths_m(b))
            if flags["flat"]:
                c_hi = np.minimum(c_hi, slot * (1 - 2 * _MARGIN))
            else:
                c_lo = np.maximum(c_lo, slot * (1 + 2 * _MARGIN))
        if flags["non_cubic"]:
            c_hi = np.minimum(c_hi, p.ab_ratio_max * b / (NON_CUBIC_RATIO * (1 + 2 * _MARGIN)))
        c = r.uniform(c_lo, np.maximum(c_lo, c_hi))
        a_lo, a_hi = b.copy(), p.ab_ratio_max * b
        if flags["non_cubic"]:
            a_lo = np.maximum(a_lo, NON_CUBIC_RATIO * (1 + 2 * _MARGIN) * c)
        else:
            a_hi = np.minimum(a_hi, NON_CUBIC_RATIO * (1 - 2 * _MARGIN) * c)
        long_m = LONG_STONE_LENGTH_MM * 1e-3
        if flags["long"]:
            a_lo = np.maximum(a_lo, long_m * (1 + 2 * _MARGIN))
        else:
            a_hi = np.minimum(a_hi, long_m * (1 - 2 * _MARGIN))
        a = r.uniform(a_lo, np.maximum(a_lo, a_hi))
        ok = (c_hi > c_lo) & (a_hi > a_lo) & self._fits(a, b, c, group, flags, _MARGIN)
        return np.column_stack([a, b, c])[ok]

    def _scale_to_mass(self, dims, mass, density, group, flags):
        """Rescale target forms so their predicted mass is `mass`; keep those still in the class."""
        predicted = density * self.volume_factor * dims.prod(axis=1)
        scaled = dims * np.cbrt(mass / predicted)[:, None]
        ok = self._fits(*scaled.T, group, flags, _MARGIN)
        if ok.any():
            return scaled[ok]
        # the mass lies outside what the class can reach: offer its smallest forms
        return dims[np.argsort(dims[:, 1])[: max(1, len(dims) // 8)]]

    # -- stones ---------------------------------------------------------------------------
    def _next_material(self):
        """The material furthest below its mass fraction (deterministic, exact proportions)."""
        lack = self._fraction * self._material_mass.sum() - self._material_mass
        return int(np.argmax(lack + 1e-12 * self._fraction))

    def _candidates(self, dims):
        semi = dims / (2 * self.shrink)
        pts = geometry.ellipsoid_surface_points(self.rng, semi, self.params.n_vertices)
        a, b, c, da, db = geometry.evaluate_dimensions(pts)
        return pts, semi, np.column_stack([a, b, c]), da, db

    def _stone(self, pts, dims, da, db, stone_flags_row, material, group_index):
        vertices, faces = geometry.convex_hull(pts)
        volume, centroid = geometry.volume_and_centroid(vertices, faces)
        flat, nc, long = (bool(f) for f in stone_flags_row)
        return Stone(vertices, faces, *map(float, dims), da, db, volume, centroid,
                     volume * self._density[material], material, group_index, flat, nc, long)

    def _matches(self, dims, group, flags):
        """Which candidates fall in the class, and every candidate's (flat, non_cubic, long)."""
        g = sieve_group(dims[:, 1])
        flat, nc, long = stone_flags(*dims.T)
        ok = (g == group.index) & (nc == flags["non_cubic"]) & (long == flags["long"])
        if "flat" in flags:
            ok &= flat == flags["flat"]
        return ok, np.column_stack([flat, nc, long])

    def _accept(self, stone, ledger):
        self.stones.append(stone)
        self._material_mass[stone.material] += stone.mass
        ledger.book(stone)

    def _tick(self, group):
        self._batches += 1
        if self._batches > _MAX_BATCHES:
            raise GenerationError(f"{self.objective.name}: group {group.name} still lacks mass after "
                                  f"{_MAX_BATCHES} batches of candidates; the objective is not reachable")

    def _batch(self, group, flags, ledger):
        """One batch for the class `flags`; returns False when the class should be given up."""
        self._tick(group)
        material = self._next_material()
        density = self._density[material]
        cap = ledger.cap(flags)
        dims = self._draw_targets(group, flags, self.params.batch)
        if len(dims) == 0:
            return False
        typical = np.median(density * self.volume_factor * dims.prod(axis=1))
        aim = cap < 1.5 * typical
        if aim:
            dims = self._scale_to_mass(dims, cap, density, group, flags)
        pts, semi, measured, da, db = self._candidates(dims)
        ok, fl = self._matches(measured, group, flags)
        stones = []
        for i in np.nonzero(ok)[0]:
            s = self._stone(pts[i], measured[i], da[i], db[i], fl[i], material, group.index)
            stones.append(s)
            if not aim:
                if s.mass > ledger.cap(flags):
                    break
                self._accept(s, ledger)
                material = self._next_material()
                density = self._density[material]
                if ledger.cap(flags) < 1.5 * typical:
                    break
        self._learn(measured, semi, [s.volume / (s.a * s.b * s.c) for s in stones])
        if aim and stones:
            best = max(stones, key=ledger.gain)
            if ledger.gain(best) > 0:
                self._accept(best, ledger)
                return True
            return False
        return True

    def _drawable(self, group, flags):
        """Whether the class has room for any form at all (cached; its own RNG stream)."""
        key = (group.index, tuple(sorted(flags.items())))
        if key not in self._drawable_cache:
            saved, self.rng = self.rng, np.random.default_rng(0)
            self._drawable_cache[key] = len(self._draw_targets(group, flags, 4096)) > 0
            self.rng = saved
        return self._drawable_cache[key]

    def _fill_group(self, group):
        ledger = _Ledger(group)
        failures = 0
        while ledger.total > 0:
            combos = [f for f in ledger.combos() if self._drawable(group, f)]
            if not combos:
                raise GenerationError(f"{self.objective.name}: no stone shape fits size group "
                                      f"{group.name} with a/b <= {self.params.ab_ratio_max:g}, "
                                      f"c/b >= {self.params.cb_ratio_min:g}")
            flags = combos[0]
            if self._batch(group, flags, ledger):
                failures = 0
                continue
            failures += 1
            if failures >= 4:
                failures = 0
                if not ledger.close_binding_side(flags):
                    break    # nothing small enough for the last missing mass: closest is reached
        return ledger

    def _top_up(self, ledgers):
        """Add the smallest stones needed to reach at least the objective total mass."""
        group = min(self.objective.groups, key=lambda g: g.upper)
        ledger = ledgers[group.index]
        while sum(s.mass for s in self.stones) < self.objective.total_mass:
            missing = self.objective.total_mass - sum(s.mass for s in self.stones)
            flags = next(f for f in ledger.combos() if self._drawable(group, f))
            self._tick(group)
            material = self._next_material()
            dims = self._draw_targets(group, flags, self.params.batch)
            if len(dims) == 0:
                continue
            dims = self._scale_to_mass(dims, missing, self._density[material], group, flags)
            pts, semi, measured, da, db = self._candidates(dims)
            ok, fl = self._matches(measured, group, flags)
            options = [self._stone(pts[i], measured[i], da[i], db[i], fl[i], material, group.index)
                       for i in np.nonzero(ok)[0]]
            enough = [s for s in options if s.mass >= missing]
            if enough:
                self._accept(min(enough, key=lambda s: s.mass), ledger)
            elif options:
                self._accept(max(options, key=lambda s: s.mass), ledger)

    def run(self, progress=None):
        """Generate every group, largest first, then top up to the objective total mass."""
        ledgers = {}
        for group in sorted(self.objective.groups, key=lambda g: -g.upper):
            ledgers[group.index] = self._fill_group(group)
            if progress is not None:
                progress(group)
        self._top_up(ledgers)
        return self.stones


def generate(objective, seed, params=FormParams(), progress=None):
    """Stones of one database (list of Stone). Raises GenerationError / ObjectiveError."""
    if not objective.groups:
        raise ObjectiveError("grading", "the grading puts no mass in any size group")
    return FormGenerator(objective, seed, params).run(progress)
