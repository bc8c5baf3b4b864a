"""The biaxial rig: a ``Simulation`` plus what the rig knows about it (which wall segments
are the platens and the sides, the membrane's servo groups, which stones came from which
library entries), its size and the stresses on its walls, and the membrane kept spanning
the platens (a rig operation applied between engine runs)."""
from dataclasses import dataclass, field

import numpy as np

from ..base import Rig
from .params import BiaxialParams

PLATEN, MEMBRANE = 2, 3      # wall materials: platens with Table 4.2's friction, side walls without


@dataclass
class BiaxialLayout:
    bottom: list = field(default_factory=list)    # wall segment ids
    top: list = field(default_factory=list)
    left: list = field(default_factory=list)      # every segment of a side
    right: list = field(default_factory=list)
    left_groups: list = field(default_factory=list)   # membrane: segment ids per servo, bottom up
    right_groups: list = field(default_factory=list)
    stone_library_index: list = field(default_factory=list)
    stone_material: list = field(default_factory=list)
    n_stone_balls: int = 0
    bonds_library: int = 0
    bonds_installed: int = 0
    seed: int = 0
    database: str = ""
    library: str = ""
    stage_steps: dict = field(default_factory=dict)
    # stages that stopped at their step limit, not at their criterion: one line each
    stages_at_limit: list = field(default_factory=list)
    # per settling stage its end: steps, mean stone-ball speed [m/s], the stones' force ratio;
    # "at rest": the stones' force ratio when the assembly ends (deposition.stone_force_ratio)
    stage_end: dict = field(default_factory=dict)
    stone_model: str = "bonded"     # how the stones are modelled now (ballaststudy.stones)


class BiaxialRig(Rig):
    Layout = BiaxialLayout
    Params = BiaxialParams
    title = "cyclic biaxial case: assembled specimen"
    kind = "biaxial"

    def wall_groups(self):
        lay = self.layout
        return {"bottom": lay.bottom, "top": lay.top, "left": lay.left, "right": lay.right}

    def _x(self, ids):
        return float(self.sim.walls.seg[ids[0], 0])

    def side_groups(self, side):
        """Segment ids per side servo, bottom up: one group (the rigid wall) or n."""
        lay = self.layout
        groups = lay.left_groups if side == "left" else lay.right_groups
        return groups or [lay.left if side == "left" else lay.right]

    def side_x(self, side):
        """x of each servo group of a side, bottom up."""
        return np.array([self._x(g) for g in self.side_groups(side)])

    def width(self):
        """Mean width between the sides (area / height: the membrane's segments span equal
        heights), as the area correction of a triaxial test."""
        return float(np.mean(self.side_x("right") - self.side_x("left")))

    def bottom_y(self):
        """y of the bottom platen's face (it does not move)."""
        return float(self.sim.walls.seg[self.layout.bottom[0], 1])

    def height(self):
        return float(self.sim.walls.seg[self.layout.top[0], 1]) - self.bottom_y()

    def stresses(self):
        """(sigma_axial at the top platen, sigma_left, sigma_right) [Pa], compression +."""
        f = self.sim.wall_force()
        t, lay = self.sim.thickness, self.layout
        w, h = self.width(), self.height()
        return (float(f[lay.top, 1].sum()) / (w * t), float(-f[lay.left, 0].sum()) / (h * t),
                float(f[lay.right, 0].sum()) / (h * t))


def place_membrane(rig):
    """Each side's n membrane segments span 1/n of the specimen height between the platens
    (their x kept; the extensions beyond the platens follow). Returns the segment length."""
    lay, seg = rig.layout, rig.sim.walls.seg
    bottom, top = float(seg[lay.bottom[0], 1]), float(seg[lay.top[0], 1])
    n = len(lay.left_groups)
    y = np.linspace(bottom, top, n + 1)
    for side in ("left", "right"):
        down = side == "left"              # the left chain runs top down, the right bottom up
        for k, group in enumerate(rig.side_groups(side)):
            lo, hi = y[k], y[k + 1]
            rig.sim.set_segment_y(group[0], *((hi, lo) if down else (lo, hi)))
            if len(group) > 1:             # an extension, joined at the chain's end node
                joint = lo if k == 0 else hi
                starts_there = (k == 0) == down
                rig.sim.set_segment_y(group[1], *((joint, None) if starts_there else (None, joint)))
    return (top - bottom) / n
