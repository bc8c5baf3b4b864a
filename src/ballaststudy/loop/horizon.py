"""The long-term horizon by measured error (issue 34): which accumulation law carries a
measured curve furthest, and how far off it lands.

Every law of loop/accumulation.py is fitted to each measured curve on its points up to
N_fit only (e.g. 1e3 and 1e4 cycles) and predicts the curve's last point (up to ~5e5
cycles); the error there, predicted - measured in strain, is the law's extrapolation error
on real ballast. Laws are compared on the same curves: a curve enters an N_fit when it has a
point beyond N_fit and enough points up to it for the law with most parameters, so no law
is judged on an easier set. A law that cannot be fitted to an entered curve counts as an
infinite error there. The law with the smallest median |error| is chosen per N_fit; its
90th percentile |error| over the curves is the uncertainty the loop states with its
extrapolation. Digitised points read just left of N = 1 on a log axis are the first
loading, N = 1.
"""
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..inputs import open_netcdf
from .accumulation import LAWS, PARAMETER_NAMES, fit_law

STATED_QUANTILE = 0.9        # the stated uncertainty: this quantile of |error| over the curves


@dataclass(frozen=True)
class LongTermLaw:
    """The accumulation law the measured curves chose and its error measured on them."""
    name: str
    fit_cycles: float        # N_fit at which the error was measured
    stated_error: float      # STATED_QUANTILE |error| at the curves' last points (strain)
    curves: int              # measured curves it was judged on


def measured_curve(path, quantity):
    """(N, values) of a measured test's curve, finite points sorted by N; N < 1 (the first
    loading, digitised) taken as 1."""
    ds = open_netcdf(path, "measured", require=(quantity,))
    n, v = ds["cycle"].values.astype(float), ds[quantity].values.astype(float)
    keep = np.isfinite(v)
    order = np.argsort(n[keep], kind="stable")
    return np.maximum(n[keep][order], 1.0), v[keep][order]


def enters(n, fit_cycles):
    """Whether a curve (its N) is judged at N_fit = fit_cycles: a point beyond it, and more
    distinct N up to it than the law with most parameters has."""
    most = max(len(p) for p in PARAMETER_NAMES.values())
    return n.max() > fit_cycles and np.unique(n[n <= fit_cycles]).size > most


def extrapolated_last(law, n, v, fit_cycles):
    """The law fitted on N <= fit_cycles, evaluated at the curve's last N; NaN where it
    cannot be fitted (too few points, no convergence, a power law through zero strain)."""
    fitted = n <= fit_cycles
    try:
        fit = fit_law(law, n[fitted], v[fitted])
    except (RuntimeError, ValueError):
        return float("nan")
    return float(LAWS[law](n[-1], fit.params))


def horizon_table(curves, fit_cycles, quantity="axial_strain"):
    """xarray Dataset of the extrapolation errors: curves {test: (N, values)}; fit_cycles the
    N_fit values. Per (test, law, fit_cycles): the prediction at the last point and its error
    (NaN where the test does not enter); per (law, fit_cycles): the median and
    STATED_QUANTILE |error|, curves entered and fitted; per fit_cycles: the chosen law."""
    tests, laws = list(curves), list(LAWS)
    shape = (len(tests), len(laws), len(fit_cycles))
    predicted = np.full(shape, np.nan)
    entered = np.zeros((len(tests), len(fit_cycles)), bool)
    for i, (n, v) in enumerate(curves.values()):
        for k, fc in enumerate(fit_cycles):
            entered[i, k] = enters(n, fc)
            if entered[i, k]:
                predicted[i, :, k] = [extrapolated_last(law, n, v, fc) for law in laws]
    last_n = np.array([n[-1] for n, _ in curves.values()])
    last_v = np.array([v[-1] for _, v in curves.values()])
    error = predicted - last_v[:, None, None]
    ds = xr.Dataset(
        {"predicted_last": (("test", "law", "fit_cycles"), predicted,
                            {"units": "1", "long_name": f"law fitted on N <= fit_cycles: {quantity} at the last point"}),
         "error": (("test", "law", "fit_cycles"), error,
                   {"units": "1", "long_name": f"predicted - measured {quantity} at the last point (NaN: not "
                                              "entered, or the law could not be fitted)"}),
         "entered": (("test", "fit_cycles"), entered.astype(np.int8),
                     {"units": "1", "long_name": "1: the curve has a point beyond fit_cycles and enough up to it"}),
         "last_cycle": ("test", last_n, {"units": "1", "long_name": "load cycle N of the curve's last point"}),
         "measured_last": ("test", last_v, {"units": "1", "long_name": f"measured {quantity} at the last point"})},
        coords={"test": ("test", tests, {"long_name": "measured test"}),
                "law": ("law", laws, {"long_name": "accumulation law (loop/accumulation.py)"}),
                "fit_cycles": ("fit_cycles", np.asarray(fit_cycles, float),
                               {"units": "1", "long_name": "N_fit: the law sees the points up to this load cycle"})},
        attrs={"Conventions": "CF-1.8", "title": "long-term horizon: accumulation laws' extrapolation error on "
               "measured curves", "quantity": quantity, "stated_quantile": STATED_QUANTILE,
               "comment": "a law's |error| counts as infinite where it could not be fitted to an entered curve"})
    return ds.assign(_summary(ds))


def _summary(ds):
    """Per (law, fit_cycles): median and stated-quantile |error| and curves fitted; per
    fit_cycles: curves entered and the chosen law (smallest median; '' if none entered)."""
    entered = ds["entered"].values.astype(bool)
    err = np.abs(ds["error"].values)
    err = np.where(np.isnan(err) & entered[:, None, :], np.inf, err)   # entered, no fit: infinite
    median = np.full(err.shape[1:], np.nan)
    stated = np.full(err.shape[1:], np.nan)
    for k in range(err.shape[2]):
        rows = err[entered[:, k], :, k]
        if rows.size:
            median[:, k] = np.quantile(rows, 0.5, axis=0, method="inverted_cdf")
            stated[:, k] = np.quantile(rows, STATED_QUANTILE, axis=0, method="inverted_cdf")
    laws = ds["law"].values
    chosen = [str(laws[np.argmin(median[:, k])]) if entered[:, k].any() else "" for k in range(err.shape[2])]
    fitted = (np.isfinite(err) & entered[:, None, :]).sum(axis=0)
    return {"median_abs_error": (("law", "fit_cycles"), median, {"units": "1", "long_name": "median |error| over the entered curves (inf: the law could not be fitted to more than half)"}),
            "stated_abs_error": (("law", "fit_cycles"), stated, {"units": "1", "long_name": f"{STATED_QUANTILE:g} quantile of |error| over the entered curves: the uncertainty stated with the law's extrapolation"}),
            "curves_fitted": (("law", "fit_cycles"), fitted.astype(np.int32), {"units": "1", "long_name": "entered curves the law could be fitted to"}),
            "curves_entered": ("fit_cycles", entered.sum(axis=0).astype(np.int32), {"units": "1", "long_name": "curves judged at this N_fit"}),
            "chosen_law": ("fit_cycles", np.array(chosen, dtype=object), {"long_name": "the law with the smallest median |error| ('' : no curve entered)"})}


def chosen_for(ds, cycles):
    """The LongTermLaw the loop uses for a DEM horizon of `cycles`: the one chosen at the
    smallest N_fit at or beyond it (the nearest measured statement; fitted on fewer cycles
    a law can only err more), else at the largest; None if no curve entered there."""
    fits = ds["fit_cycles"].values
    k = int(np.argmax(fits >= cycles)) if (fits >= cycles).any() else len(fits) - 1
    law = str(ds["chosen_law"].values[k])
    if not law:
        return None
    return LongTermLaw(law, float(fits[k]), float(ds["stated_abs_error"].sel(law=law).values[k]),
                       int(ds["curves_entered"].values[k]))
