"""The box-test rig: a ``Simulation`` plus what the rig knows about it (which walls are the
bottom segments and the sides, which clump is the pressing plate and which the loading
ball, which stones came from which library entries). Saved as one netCDF file that holds
the inspectable state and the engine checkpoint bytes (bitwise restore)."""
from dataclasses import dataclass, field

import numpy as np

from .base import Rig
from .params import RigParams


@dataclass
class RigLayout:
    """Ids and geometry the rig operations need (all JSON-serialisable)."""
    bottom: list = field(default_factory=list)       # 20 bottom segment ids, left to right
    bottom_ext: list = field(default_factory=list)   # bottom outside the final width
    left: list = field(default_factory=list)         # left side-wall segment ids
    right: list = field(default_factory=list)
    left_low: int = -1                                # the side segments below height_m
    right_low: int = -1
    plate: int = -1                                   # clump id of the pressing plate
    plate_balls: list = field(default_factory=list)
    loading: int = -1                                 # clump id of the loading ball
    loading_ball: int = -1                            # its pebble (ball id)
    stone_library_index: list = field(default_factory=list)
    stone_material: list = field(default_factory=list)
    n_stone_balls: int = 0                            # balls 0..n-1 are stone balls
    bonds_library: int = 0                            # bonds the library lists
    bonds_installed: int = 0                          # bonds the engine installed
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


class BoxRig(Rig):
    """The box test: its walls (bottom segments, sides), the pressing plate and the
    loading ball."""
    Layout = RigLayout
    Params = RigParams
    title = "box-test case: assembled specimen (thesis 4.2.2)"
    kind = "box"

    def wall_groups(self):
        lay = self.layout
        return {"bottom": lay.bottom, "left": lay.left, "right": lay.right}

    def body_balls(self):
        lay = self.layout
        return {"plate": lay.plate_balls,
                "loading ball": [lay.loading_ball] if lay.loading_ball >= 0 else []}

    # ----------------------------------------------------------------- measurements
    def loading_force(self):
        """Vertical force the plate exerts on the loading ball [N] (compression +)."""
        lb = self.layout.loading
        f, _ = self.sim.clump_force(lb)
        m = float(self.sim.clumps.mass[lb])
        return float(f[1] - m * self.sim.gravity[1])   # minus its weight

    def loading_y(self):
        return float(self.sim.clumps.pos[self.layout.loading, 1])

    def bottom_forces(self):
        """Vertical force on each bottom segment [N], pushing down = positive."""
        return -self.sim.wall_force(self.layout.bottom)[:, 1]

    def side_forces(self):
        """(left, right) forces on the side walls [N], rows (fx, fy); all segments."""
        lw = self.sim.wall_force(self.layout.left).sum(axis=0)
        rw = self.sim.wall_force(self.layout.right).sum(axis=0)
        return np.vstack([lw, rw])

    def plate_state(self):
        c = self.layout.plate
        s = self.sim.clumps
        return float(s.pos[c, 0]), float(s.pos[c, 1]), float(s.theta[c])

    def weight(self):
        """Total weight of live balls and clumps (plate, loading ball) [N] (positive)."""
        b, c, g = self.sim.balls, self.sim.clumps, -self.sim.gravity[1]
        free = (b.alive == 1) & (b.clump < 0)
        return float((b.mass[free].sum() + c.mass.sum()) * g)
