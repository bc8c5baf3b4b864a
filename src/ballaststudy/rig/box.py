"""The box-test rig: a ``Simulation`` plus what the rig knows about it (which walls are the
bottom segments and the sides, which clump is the pressing plate and which the loading
ball, which stones came from which library entries). Saved as one netCDF file that holds
the inspectable state and the engine checkpoint bytes (bitwise restore)."""
import json
import os
import tempfile
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from ..atomic import atomic_path
from ..dem import Simulation
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


class BoxRig:
    """Owns the Simulation, the layout and the parameters of one case."""

    def __init__(self, sim, layout, params):
        self.sim = sim
        self.layout = layout
        self.params = params

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

    def stone_balls(self):
        """Ids of live stone balls (not plate, not loading ball)."""
        b = self.sim.balls
        ids = np.arange(self.layout.n_stone_balls)
        return ids[b.alive[ids] == 1]

    def fragments(self):
        """Fragment id per stone ball (-1 for dead balls): Simulation.fragments."""
        return self.sim.fragments(self.layout.n_stone_balls).astype(np.int32)

    def weight(self):
        """Total weight of live balls and clumps (plate, loading ball) [N] (positive)."""
        b, c, g = self.sim.balls, self.sim.clumps, -self.sim.gravity[1]
        free = (b.alive == 1) & (b.clump < 0)
        return float((b.mass[free].sum() + c.mass.sum()) * g)

    # ----------------------------------------------------------------- I/O
    def engine_bytes(self):
        fd, tmp = tempfile.mkstemp(suffix=".npz")
        os.close(fd)
        try:
            self.sim.save_checkpoint(tmp)
            with open(tmp, "rb") as f:
                return f.read()
        finally:
            os.unlink(tmp)

    @staticmethod
    def sim_from_bytes(data, source="checkpoint"):
        fd, tmp = tempfile.mkstemp(suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            try:
                return Simulation.load_checkpoint(tmp)
            except (ValueError, KeyError) as err:
                raise ValueError(f"{source}: the engine state cannot be restored "
                                 f"({str(err).replace(tmp, 'engine checkpoint')}); "
                                 "assemble the case again") from None
        finally:
            os.unlink(tmp)

    def to_dataset(self, attrs=None):
        """Inspectable state (balls, bonds, walls, plate) + engine checkpoint bytes."""
        sim, lay = self.sim, self.layout
        b = sim.balls
        frag = np.full(len(b), -1, np.int32)
        frag[: lay.n_stone_balls] = self.fragments()
        bd = sim.bonds
        ds = xr.Dataset(
            {"x": ("ball", b.pos[:, 0], {"units": "m", "long_name": "ball centre x"}),
             "y": ("ball", b.pos[:, 1], {"units": "m", "long_name": "ball centre y"}),
             "radius": ("ball", b.rad, {"units": "m", "long_name": "ball radius"}),
             "stone": ("ball", b.stone, {"long_name": "stone id (-1: plate / loading ball)"}),
             "material": ("ball", b.mat, {"long_name": "material id", "flag_values": [0, 1, 2],
                                          "flag_meanings": "hard soft steel"}),
             "alive": ("ball", b.alive, {"long_name": "1 = ball exists"}),
             "fragment": ("ball", frag, {"long_name": "fragment id (-1: none)"}),
             "bond_i": ("bond", bd.i), "bond_j": ("bond", bd.j),
             "bond_intact": ("bond", sim.intact_bonds(),
                             {"long_name": "bond has an intact element"}),
             "wall_segment": (("wall", "xy2"), sim.walls.seg, {"units": "m"}),
             "engine_checkpoint": ("nbytes", np.frombuffer(self.engine_bytes(), np.uint8),
                                   {"long_name": "ballaststudy.dem checkpoint (npz bytes)"})},
            attrs={"Conventions": "CF-1.8",
                   "title": "box-test case: assembled specimen (thesis 4.2.2)",
                   "rig_layout_json": json.dumps(vars(lay)),
                   "rig_params_json": json.dumps(self.params.to_dict()),
                   "database": lay.database, "seed": lay.seed, "step": sim.step,
                   **(attrs or {})})
        ds["bond_intact"] = ds["bond_intact"].astype(np.int8)
        return ds

    def save(self, path, attrs=None):
        with atomic_path(path) as tmp:
            self.to_dataset(attrs).to_netcdf(tmp)
        return path

    @classmethod
    def from_parts(cls, engine, layout, params, source="checkpoint"):
        """From engine checkpoint bytes and the layout / parameter dicts."""
        return cls(cls.sim_from_bytes(engine, source), RigLayout(**layout), RigParams(**params))

    @classmethod
    def load(cls, path):
        with xr.open_dataset(path) as ds:
            data = np.asarray(ds["engine_checkpoint"].values, np.uint8).tobytes()
            lay = RigLayout(**json.loads(ds.attrs["rig_layout_json"]))
            prm = RigParams(**json.loads(ds.attrs["rig_params_json"]))
        return cls(cls.sim_from_bytes(data, path), lay, prm)
