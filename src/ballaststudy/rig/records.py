"""``metrics.nc`` of one case: the per-cycle records of the loading run (dimension
``cycle``), the loading-ball time series, the breakage records and the snapshots the
behaviour metrics need, plus the behaviours themselves.

Settlement and breakage rates follow directly from the records (thesis 4.5.1, eqs.
4.6-4.8) and are written here; the force propagation angle, void ratio and ghost
particles come from ``ballaststudy.metrics`` when that package is installed (it is
called with the arrays recorded here; see ``behaviours``)."""
import json

import numpy as np
import xarray as xr

from ..metrics import metrics_dataset
from ..metrics.output import write_metrics as write_metrics_file
from ..metrics.breakage import mode_codes
from .loading import CYCLE_FIELDS


def breakage_records(run):
    """Breakages since loading began: dict of arrays incl. the cycle each fell in
    (-1 = static pre-loading / unloading)."""
    br = run.rig.stones.breakages(run.rig.sim)
    k0 = run.s.log0
    out = {k: np.asarray(v[k0:]) for k, v in br.items()}
    out["mode_code"] = mode_codes(out["mode"])
    ends = np.asarray(run.cyc["cycle_end_step"], float)
    cyc = np.searchsorted(ends, out["step"], side="left")
    start = (ends[0] - run.cyc["cycle_steps"][0]) if len(ends) else np.inf
    cyc = np.where(out["step"] <= start, -1, cyc)
    cyc = np.where(cyc >= len(ends), len(ends), cyc)     # after the last finished cycle
    out["cycle"] = cyc.astype(np.int32)
    return out


def behaviours(run, ds, n_elements):
    """The behaviours per cycle: ``ballaststudy.metrics`` results computed at the end of
    every cycle (``LoadingRun.behaviours``) when that package is installed; otherwise
    settlement and breakage rates straight from the records (eqs. 4.6-4.8)."""
    rows = run.s.rows
    if rows and all(rows):
        ds.attrs["metrics_package"] = "ballaststudy.metrics (compute_cycle per cycle)"
        return {k: v for k, v in metrics_dataset(rows).data_vars.items()}
    ds.attrs["metrics_package"] = ("not installed: settlement and breakage rates from the "
                                   "rig's records only")
    out = {}
    out["settlement"] = xr.DataArray(
        ds.attrs["y_reference"] - ds["y_at_settlement_force"].values, dims="cycle",
        attrs={"units": "m", "long_name": "settlement: drop of the loading ball at the "
               "settlement force on the loading branch since the end of static loading"})
    for name, col, text in (("breakage_rate_tension", "elements_broken_tension", "tension"),
                            ("breakage_rate_shear", "elements_broken_shear", "shear")):
        out[name] = xr.DataArray(ds[col].values / max(n_elements, 1), dims="cycle",
                                 attrs={"units": "1", "long_name": f"breakage rate in {text} "
                                        "(broken FJ elements / installed, eq. 4.6/4.7)"})
    out["breakage_rate"] = xr.DataArray(
        out["breakage_rate_tension"].values + out["breakage_rate_shear"].values, dims="cycle",
        attrs={"units": "1", "long_name": "breakage rate (eq. 4.8)"})
    return out


def to_dataset(run, attrs=None):
    rig, s = run.rig, run.s
    lay = rig.layout
    n = len(run.cyc["cycle_end_step"])
    data = {}
    for k, (units, long_name) in CYCLE_FIELDS.items():
        v = np.asarray(run.cyc[k], float)
        if units == "1":
            v = v.astype(np.int64)
        data[k] = ("cycle", v, {"units": units, "long_name": long_name})
    nb = len(run.bottom)
    bottom = np.asarray(run.bottom, float).reshape(nb, -1)[:n]
    side = np.asarray(run.side, float).reshape(nb, 2, 2)[:n]
    data["bottom_force"] = (("cycle", "segment"), bottom,
                            {"units": "N", "long_name": "vertical force on each bottom segment "
                             "at peak load (downwards +)"})
    data["side_force"] = (("cycle", "side", "component"), side,
                          {"units": "N", "long_name": "force of the balls on the side walls "
                           "at peak load"})
    seg = rig.sim.walls.seg[lay.bottom]
    coords = {"cycle": ("cycle", np.arange(n), {"long_name": "loading cycle"}),
              "segment_x": ("segment", 0.5 * (seg[:, 0] + seg[:, 2]),
                            {"units": "m", "long_name": "bottom segment centre x"}),
              "side": ("side", ["left", "right"], {"units": "1", "long_name": "container side wall"}),
              "component": ("component", ["x", "y"], {"units": "1", "long_name": "force component"})}
    # time series of the loading ball
    sm = run.samples
    data["sample_step"] = ("sample", np.asarray(sm["step"], np.int64), {"units": "1",
                           "long_name": "engine step of the sample"})
    data["sample_cycle"] = ("sample", np.asarray(sm["cycle"], np.int32), {"units": "1",
                            "long_name": "cycle of the sample (-1: static / unloading)"})
    data["sample_force"] = ("sample", np.asarray(sm["force"]), {"units": "N",
                            "long_name": "loading-ball force"})
    data["sample_y"] = ("sample", np.asarray(sm["y"]), {"units": "m",
                        "long_name": "loading-ball height"})
    # breakage records
    add_breakage_records(run, data)
    # snapshots (every snapshot_every cycles, at peak load)
    nn = lay.n_stone_balls
    b = rig.sim.balls
    data["ball_radius"] = ("ball", b.rad[:nn], {"units": "m", "long_name": "ball radius"})
    data["ball_stone"] = ("ball", b.stone[:nn], {"units": "1", "long_name": "stone id"})
    data["ball_material"] = ("ball", b.mat[:nn].astype(np.int8),
                             {"units": "1", "long_name": "ball material",
                              "flag_values": np.array([0, 1], np.int8), "flag_meanings": "hard soft"})
    data["ball_alive"] = ("ball", b.alive[:nn], {"units": "1",
                                                 "long_name": "1 = ball exists at the end"})
    ns = len(run.snap_cycles)
    data["snapshot_cycle"] = ("snapshot", np.asarray(run.snap_cycles, np.int64),
                              {"units": "1", "long_name": "cycle of the snapshot"})
    data["snapshot_x"] = (("snapshot", "ball"), np.asarray(run.snap_pos, np.float32).reshape(ns, nn, 2)[..., 0],
                          {"units": "m", "long_name": "ball x at peak load"})
    data["snapshot_y"] = (("snapshot", "ball"), np.asarray(run.snap_pos, np.float32).reshape(ns, nn, 2)[..., 1],
                          {"units": "m", "long_name": "ball y at peak load"})
    data["snapshot_fragment"] = (("snapshot", "ball"), np.asarray(run.snap_frag, np.int32).reshape(ns, nn),
                                 {"units": "1", "long_name": "fragment id (-1: ball deleted)"})
    cnt = [len(c["i"]) for c in run.snap_contacts]
    data["snapshot_contact_count"] = ("snapshot", np.asarray(cnt, np.int64),
                                      {"sample_dimension": "contact", "units": "1",
                                       "long_name": "contacts carrying force at peak load"})
    for k, units, ln in (("i", "1", "ball i"), ("j", "1", "ball j (< 0: wall segment -1-j)"),
                         ("fx", "N", "force on j, x"), ("fy", "N", "force on j, y"),
                         ("x", "m", "contact point x"), ("y", "m", "contact point y")):
        parts = [c[k] for c in run.snap_contacts]
        v = np.concatenate(parts) if parts else np.zeros(0)
        v = v.astype(np.int32) if k in ("i", "j") else v.astype(np.float32)
        data["contact_" + k] = ("contact", v, {"units": units, "long_name": "contact: " + ln})
    wall_kind = np.zeros(len(rig.sim.walls), np.int8)
    wall_kind[lay.bottom] = 1
    wall_kind[lay.left] = 2
    wall_kind[lay.right] = 3
    data["wall_kind"] = ("wall", wall_kind, {"units": "1", "long_name": "container wall segment",
                                             "flag_values": np.array([0, 1, 2, 3], np.int8),
                                             "flag_meanings": "outside bottom left right"})
    n_bonds = int(s.n_bonds0) * rig.stones.elements_per_unit(rig.sim)
    ds = xr.Dataset(data, coords=coords, attrs={
        "Conventions": "CF-1.8",
        "title": "box-test case: per-cycle records and behaviours (thesis 4.2.3, 4.5.1)",
        "database": lay.database, "seed": lay.seed, "cycles_requested": run.cycles,
        "stone_model": lay.stone_model,
        "stone_splitting_json": json.dumps(rig.sim.crushing_settings()),
        "y_reference": s.y_ref, "static_end_step": s.static_end_step,
        "static_mean_forces_N": json.dumps(s.static_mean),
        "static_mean_wall_forces_N": json.dumps(s.static_walls),
        "flat_joint_elements_at_loading_start": n_bonds,
        "thickness_m": rig.sim.thickness,
        "force_convention": "2D forces per thickness t (PFC2D); thesis loads applied directly",
        "rig_params_json": json.dumps(rig.params.to_dict()),
        "rig_layout_json": json.dumps(vars(lay)), **(attrs or {})})
    for name, da in behaviours(run, ds, n_bonds).items():
        ds[name] = da
    return ds


def write_metrics(run, path, attrs=None):
    """metrics.nc of a run, through the one metrics writer (every variable with units and
    long_name, atomic)."""
    ds = to_dataset(run, attrs)
    write_metrics_file(path, ds)
    return ds


def add_breakage_records(run, data):
    """The breakage records as ``breakage_<name>`` variables of ``data``."""
    br = breakage_records(run)
    for k, units, ln in BREAKAGE_VARIABLES:
        a = {"units": units, "long_name": f"breakage: {ln}"}
        if k == "mode_code":
            modes = run.rig.stones.break_modes
            a.update(flag_values=mode_codes(modes), flag_meanings=" ".join(modes))
        data["breakage_" + k] = ("breakage", br[k], a)


BREAKAGE_VARIABLES = (("step", "1", "engine step"), ("cycle", "1", "cycle (-1: before cycling)"),
                      ("mode_code", "1", "mode"), ("stone", "1", "stone id"),
                      ("i", "1", "ball i"), ("j", "1", "ball j"), ("x", "m", "x"),
                      ("y", "m", "y"), ("stress", "Pa", "stress at failure"))


def cyclic_dataset(run, channel_units, title, attrs=None):
    """metrics.nc of any cyclic run: its cycle records, its time series (one variable per
    channel, ``channel_units``: name -> (units, long name)), the breakage records and the
    behaviours per cycle (ballaststudy.metrics' variable table)."""
    n = len(run.cyc["cycle_end_step"])
    data = {}
    for k, (units, long_name) in run.CYCLE_FIELDS.items():
        v = np.asarray(run.cyc[k], float)
        data[k] = ("cycle", v.astype(np.int64) if units == "1" else v,
                   {"units": units, "long_name": long_name})
    sm = run.samples
    data["sample_step"] = ("sample", np.asarray(sm["step"], np.int64),
                           {"units": "1", "long_name": "engine step of the sample"})
    data["sample_cycle"] = ("sample", np.asarray(sm["cycle"], np.int32),
                            {"units": "1", "long_name": "cycle of the sample (-1: before cycling)"})
    for name, (units, long_name) in channel_units.items():
        data["sample_" + name] = ("sample", np.asarray(sm[name]),
                                  {"units": units, "long_name": long_name})
    add_breakage_records(run, data)
    ds = xr.Dataset(data, coords={"cycle": ("cycle", np.arange(n),
                                            {"units": "1", "long_name": "loading cycle"})},
                    attrs={"Conventions": "CF-1.8", "title": title,
                           "database": run.rig.layout.database, "seed": run.rig.layout.seed,
                           "stone_model": run.rig.layout.stone_model,
                           "stone_splitting_json": json.dumps(run.rig.sim.crushing_settings()),
                           "cycles_requested": run.cycles,
                           "thickness_m": run.rig.sim.thickness,
                           "rig_params_json": json.dumps(run.rig.params.to_dict()),
                           "rig_layout_json": json.dumps(vars(run.rig.layout)),
                           **(attrs or {})})
    if run.s.rows:
        for name, da in metrics_dataset(run.s.rows).data_vars.items():
            ds[name] = da
    return ds
