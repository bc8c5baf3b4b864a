"""Rigid stones: each stone (each fragment of the assembled specimen) one free clump of
its balls as pebbles; pebbles of one clump do not interact, so the stiff springs inside a
stone are gone and the timestep is set by the contacts between stones (per clump:
integrate.clump_springs). The contact law between stones, the forms and the libraries are
the bonded model's. These stones do not break: splitting is not built yet, so the
breakage record stays empty and the breakage rate is 0 by construction."""
import numpy as np

from .base import StoneModel


class RigidStones(StoneModel):
    name = "rigid"
    description = "each stone one rigid clump of its balls (unbreakable: splitting not built yet)"

    def make(self, sim, stone_balls):
        """One clump per fragment (bond-connected group) of the live ``stone_balls``:
        momentum kept, the joints inside made inactive (Simulation.make_clumps)."""
        ids = np.asarray(stone_balls, np.int64)
        n = int(ids.max()) + 1 if len(ids) else 0
        f = sim.fragments(n)[ids]
        order = np.argsort(f, kind="stable")
        cuts = np.flatnonzero(np.diff(f[order])) + 1
        return sim.make_clumps(np.split(ids[order], cuts))

    def topology(self, sim):
        """The stone's flat joints as assembled (inactive in the engine, kept as the
        record of which balls were joined), intact while both balls are in one clump: the
        same links, and so the same stone solids, as the bonded model's."""
        b, bd = sim.balls, sim.bonds
        ci, cj = b.clump[bd.i], b.clump[bd.j]
        return bd.i, bd.j, (ci >= 0) & (ci == cj) & (b.alive[bd.i] == 1) & (b.alive[bd.j] == 1)

    def breakable_units(self, sim):
        """The stones (clumps of stone balls): the unit that would split."""
        b = sim.balls
        stone = (b.clump >= 0) & (b.stone >= 0) & (b.alive == 1)
        return int(len(np.unique(b.clump[stone])))

    def elements_per_unit(self, sim):
        """A stone splits once per record."""
        return 1

    def breakages(self, sim):
        """Empty: rigid stones do not break (yet); the columns are the engine's."""
        return {k: v[:0] for k, v in sim.breakages().items()}

