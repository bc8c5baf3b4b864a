"""Rigid stones: each stone (each fragment of the assembled specimen) one free clump of
its balls as pebbles; pebbles of one clump do not interact, so the stiff springs inside a
stone are gone and the timestep is set by the contacts between stones (per clump:
integrate.clump_springs). The contact law between stones, the forms and the libraries are
the bonded model's. With splitting on (``make``'s ``splitting``: dem/crushing.py) a stone
splits in two when its characteristic stress reaches its Weibull strength, and its pieces
split again; a record is a split, and the breakage rate is splits per stone. Off, the
stones never break and the record stays empty."""
import numpy as np

from .base import StoneModel


class RigidStones(StoneModel):
    name = "rigid"
    description = "each stone one rigid clump of its balls, split in two at its Weibull strength"
    break_modes = ("split",)
    can_split = True

    def make(self, sim, stone_balls, splitting=None):
        """One clump per fragment (bond-connected group) of the live ``stone_balls``:
        momentum kept, the joints inside made inactive (Simulation.make_clumps). With
        ``splitting`` (dict of Simulation.enable_crushing's arguments) they split."""
        ids = np.asarray(stone_balls, np.int64)
        n = int(ids.max()) + 1 if len(ids) else 0
        f = sim.fragments(n)[ids]
        order = np.argsort(f, kind="stable")
        cuts = np.flatnonzero(np.diff(f[order])) + 1
        clumps = sim.make_clumps(np.split(ids[order], cuts))
        sim.bury(clumps)
        if splitting:
            sim.enable_crushing(clumps, **splitting)
        return clumps

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
        """The splits (Simulation.split_log) in the engine's breakage columns: mode
        'split', the assembled stone, the parent's centre, the characteristic stress
        reached; no bond, element or ball pair (-1)."""
        log = sim.split_log()
        n = len(log["step"])
        none = np.full(n, -1, np.int32)
        return dict(step=log["step"], time=log["time"], bond=none, elem=none.copy(), i=none.copy(),
                    j=none.copy(), stone=log["stone"], x=log["x"], y=log["y"], stress=log["stress"],
                    mode=np.array(["split"] * n, dtype=object))

