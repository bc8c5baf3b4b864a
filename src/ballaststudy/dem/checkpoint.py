"""Checkpoint: the whole Simulation state in one .npz, written atomically.

Everything the kernels read is saved (ball/wall/clump arrays, both Verlet lists with their
per-contact history and state, bonds, breakage log, counters, parameters, the contact law's
sub-models and its material-pair table), so a restored run
continues bit for bit.
"""
import json
import os
import tempfile

import numpy as np

from .law import ContactLaw
from . import params as P
from .params import new_params
from .state import Balls, Bonds, BreakLog, Clumps, Pairs, SplitLog, WallPairs, Walls

_PARTS = (("balls", Balls, "b_"), ("walls", Walls, "w_"), ("clumps", Clumps, "c_"),
          ("pairs", Pairs, "p_"), ("wpairs", WallPairs, "q_"), ("bonds", Bonds, "f_"),
          ("log", BreakLog, "l_"), ("splits", SplitLog, "k_"))
_ARRAYS = ("prm", "cnt", "eacc", "err", "coef")
_META = ("skin", "domain", "n_elements", "_prepared")
FORMAT = 3      # bump when the saved arrays change


def save_state(path, sim):
    data = {}
    for attr, _, prefix in _PARTS:
        data.update(getattr(sim, attr).to_dict(prefix))
    for name in _ARRAYS:
        data["s_" + name] = getattr(sim, name)
    meta = {k: getattr(sim, k) for k in _META}
    meta["format"] = FORMAT
    meta["law"] = list(sim.law.names)
    meta["default_row"] = list(sim._default_row)
    data["meta"] = np.array(json.dumps(meta))
    d = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=d, prefix=".ckpt-", suffix=".npz")
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def load_state(path, sim):
    with np.load(path) as z:
        d = {k: z[k] for k in z.files}
    d.setdefault("b_buried", np.zeros(len(d["b_rad"]), np.uint8))    # written before burial
    meta = json.loads(str(d["meta"]))
    if meta.get("format") != FORMAT:
        raise ValueError(f"{path}: checkpoint format {meta.get('format')} is not {FORMAT} "
                         "(written by another version of ballaststudy.dem)")
    for attr, cls, prefix in _PARTS:
        setattr(sim, attr, cls.from_dict(d, prefix))
    for name in _ARRAYS:
        setattr(sim, name, np.array(d["s_" + name]))
    n_saved = len(sim.prm)
    sim.prm = np.concatenate([sim.prm, new_params()[n_saved:]])   # parameters added since
    if n_saved <= P.CRUSH_SIGMA0_SOFT:       # one splitting law then, for every material
        sim.prm[P.CRUSH_SIGMA0_SOFT], sim.prm[P.CRUSH_M_SOFT] = sim.prm[P.CRUSH_SIGMA0], sim.prm[P.CRUSH_M]
    for k in _META:
        v = meta[k]
        setattr(sim, k, tuple(v) if isinstance(v, list) else v)
    sim.law = ContactLaw.from_names(meta["law"])
    sim._layout = sim.law.layout()
    sim._default_row = meta["default_row"]
