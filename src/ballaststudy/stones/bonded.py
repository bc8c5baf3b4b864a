"""Bonded stones (thesis 4.2.1, physics spec "Flat-joint bond"): the BPM as assembled."""
from .base import StoneModel, StoneModelError


class BondedStones(StoneModel):
    name = "bonded"
    description = "balls glued by flat joints (the thesis' BPM), breaking element by element"
    has_flat_joints = True
    break_modes = ("tension", "shear")
    gpu_batch = True

    def make(self, sim, stone_balls, splitting=None):
        """The assembly's stones are already bonded ones (they break by their joints:
        ``splitting`` is refused)."""
        if splitting:
            raise StoneModelError("bonded stones break by their flat joints, not by splitting")

    def topology(self, sim):
        """The flat joints, intact while an element of theirs is (dem.fragments)."""
        bd = sim.bonds
        return bd.i, bd.j, sim.intact_bonds()

    def breakable_units(self, sim):
        """The active flat joints (eqs. 4.6-4.8's FJ_Total at N_r = 1)."""
        return int((sim.bonds.active == 1).sum())

    def elements_per_unit(self, sim):
        """Each joint's elements N_r break one by one, each a record."""
        return int(sim.bonds.state.shape[1])

    def breakages(self, sim):
        """The engine's record of broken flat-joint elements."""
        return sim.breakages()
