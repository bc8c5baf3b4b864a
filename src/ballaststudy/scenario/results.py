"""Reading a scenario's cases back: a case's per-cycle curve, and a curve at measured N.

The simulated curve of cycle k (0-based) is the measured N = k + 1 (cycle 0 is the first
loading). A case that failed (its strain ran away, ``metrics.nc`` attribute ``failed``) has
no rows past its failure: its strain there is censored at the failure strain (at least
that, or its last value if larger) - a set that fails the specimen fits a measured curve
that did not fail badly, as it should."""
import json

import numpy as np

from ..inputs import open_netcdf


def case_curve(metrics_path, quantity, cycles):
    """((cycles,) curve, failed) of a case; a failed case's missing cycles censored."""
    ds = open_netcdf(metrics_path, "metrics")
    rows = ds[quantity].values if quantity in ds else np.zeros(0)
    curve = np.empty(cycles)
    curve[:rows.size] = rows[:cycles]
    if rows.size < cycles:
        if not ds.attrs.get("failed"):
            raise ValueError(f"{metrics_path}: {rows.size} of {cycles} cycles and not failed")
        prm = json.loads(ds.attrs["rig_params_json"])
        last = rows[-1] if rows.size else -np.inf
        curve[rows.size:] = max(prm["failure_axial_strain"], last)
    return curve, bool(ds.attrs.get("failed"))


def at_points(curve, points):
    """The curve of cycles N = 1..len(curve) at the measured N (1 <= N <= len), in ln N."""
    n = np.arange(1, curve.size + 1, dtype=float)
    return np.interp(np.log(points), np.log(n), curve)
