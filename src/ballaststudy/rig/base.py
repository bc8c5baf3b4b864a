"""What every rig is: a ``Simulation`` plus the rig's layout (which walls and clumps play
which part, which stones came from which library entries) and parameters; saved as one
netCDF file that holds the inspectable state and the engine checkpoint bytes (bitwise
restore). Stone balls are balls 0..layout.n_stone_balls-1."""
import json
import os
import tempfile

import numpy as np
import xarray as xr

from ..atomic import atomic_path
from ..dem import Simulation
from ..inputs import open_netcdf
from ..stones import stone_model


class Rig:
    """Owns the Simulation, the layout and the parameters of one case. Subclasses set
    ``Layout`` and ``Params`` (dataclasses) and ``title``."""
    Layout = Params = None
    title = "assembled specimen"
    kind = ""

    def __init__(self, sim, layout, params):
        self.sim = sim
        self.layout = layout
        self.params = params

    def stone_balls(self):
        """Ids of live stone balls (not plates, platens, loading bodies)."""
        b = self.sim.balls
        ids = np.arange(self.layout.n_stone_balls)
        return ids[b.alive[ids] == 1]

    def ball_contacts(self):
        """Ball-ball contacts carrying force: (i, j, |normal force| [N])."""
        b = self.sim.balls
        cl = self.sim.contact_list()
        ball = cl["j"] >= 0
        i, j = cl["i"][ball], cl["j"][ball]
        d = b.pos[j] - b.pos[i]
        nrm = d / np.hypot(*d.T)[:, None]
        return i, j, np.abs(cl["fx"][ball] * nrm[:, 0] + cl["fy"][ball] * nrm[:, 1])

    def wall_groups(self):
        """{name: segment ids} of the walls that bound the specimen (drawn, VTK kinds)."""
        return {}

    def body_balls(self):
        """{name: ball ids} of the bodies that are not stones (plates, loading bodies)."""
        return {}

    @property
    def stones(self):
        """The stone model of this specimen (ballaststudy.stones): what the rig asks about
        its stones."""
        return stone_model(self.layout.stone_model)

    def use_stone_model(self, name, splitting=None):
        """Make the assembled stones the model ``name``'s (a no-op for the model they are;
        ``splitting``: how rigid stones split, dem/crushing.py)."""
        if name != self.layout.stone_model:
            stone_model(name).make(self.sim, self.stone_balls(), splitting)
            self.layout.stone_model = name
            self.sim.prepare()      # the lists and the automatic dt of the new bodies

    def fragments(self):
        """Fragment id per stone ball (-1 for dead balls), from the stone model."""
        return self.stones.fragments(self.sim, self.layout.n_stone_balls).astype(np.int32)

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
             "stone": ("ball", b.stone, {"units": "1", "long_name": "stone id (-1: plate / loading ball)"}),
             "material": ("ball", b.mat, {"units": "1", "long_name": "material id", "flag_values": [0, 1, 2],
                                          "flag_meanings": "hard soft steel"}),
             "alive": ("ball", b.alive, {"units": "1", "long_name": "1 = ball exists"}),
             "fragment": ("ball", frag, {"units": "1", "long_name": "fragment id (-1: none)"}),
             "bond_i": ("bond", bd.i, {"units": "1", "long_name": "first ball of the flat-joint bond"}),
             "bond_j": ("bond", bd.j, {"units": "1", "long_name": "second ball of the flat-joint bond"}),
             "bond_intact": ("bond", sim.intact_bonds(),
                             {"units": "1", "long_name": "bond has an intact element"}),
             "wall_segment": (("wall", "xy2"), sim.walls.seg,
                              {"units": "m", "long_name": "wall segment end points (x0, y0, x1, y1)"}),
             "engine_checkpoint": ("nbytes", np.frombuffer(self.engine_bytes(), np.uint8),
                                   {"units": "1", "long_name": "ballaststudy.dem checkpoint (npz bytes)"})},
            attrs={"Conventions": "CF-1.8",
                   "title": self.title, "rig_kind": self.kind,
                   "rig_layout_json": json.dumps(vars(lay)),
                   "rig_params_json": json.dumps(self.params.to_dict()),
                   "database": lay.database, "seed": lay.seed, "step": sim.step,
                   "stone_model": lay.stone_model,
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
        return cls(cls.sim_from_bytes(engine, source), cls.Layout(**layout), cls.Params.from_record(params))

    @classmethod
    def load(cls, path):
        return cls.from_dataset(open_netcdf(path, "assembled"), path)

    @classmethod
    def from_dataset(cls, ds, source="assembled case"):
        """From a loaded assembled-case Dataset (the file's content, see ``to_dataset``)."""
        data = np.asarray(ds["engine_checkpoint"].values, np.uint8).tobytes()
        lay = cls.Layout(**json.loads(ds.attrs["rig_layout_json"]))
        prm = cls.Params.from_record(json.loads(ds.attrs["rig_params_json"]))
        return cls(cls.sim_from_bytes(data, source), lay, prm)
