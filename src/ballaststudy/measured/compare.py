"""A measured test beside its simulated cases: one netCDF on one cycle axis (the measured N
and the simulated cycle counts N = k + 1, union; NaN where a curve has no point) holding
the measured curves and the K simulated ones (dimension ``case``), plus a figure.

The simulated strains are the biaxial rig's: 2D, from the end of consolidation, the
volumetric one an area strain; the attributes say so. Nothing is fitted here."""
from pathlib import Path

import numpy as np
import xarray as xr

from ..atomic import atomic_path
from ..schema import ConfigError
from ..inputs import open_netcdf
from ..metrics.output import VARIABLES

QUANTITIES = ("axial_strain", "volumetric_strain")


def compare_dataset(measured_path, case_paths):
    measured = open_netcdf(measured_path, "measured")
    cases = [open_netcdf(p, "metrics") for p in case_paths]
    for p, ds in zip(case_paths, cases):
        if "axial_strain" not in ds and not ds.attrs.get("failed"):   # failed before cycle 1: no rows
            raise ConfigError(p, "axial_strain", "not a biaxial case's metrics.nc")
    n_sim = [np.arange(1, ds.sizes["cycle"] + 1, dtype=float) for ds in cases]
    cycle = np.unique(np.concatenate([measured["cycle"].values, *n_sim]))
    data = {}
    for q in QUANTITIES:
        units, long_name, _ = VARIABLES[q]
        if q in measured:
            full = np.full(cycle.size, np.nan)
            full[np.searchsorted(cycle, measured["cycle"].values)] = measured[q].values
            data["measured_" + q] = ("cycle", full, {"units": units,
                                                     "long_name": "measured " + long_name})
        sim = np.full((len(cases), cycle.size), np.nan)
        for k, (n, ds) in enumerate(zip(n_sim, cases)):
            if q in ds:
                sim[k, np.searchsorted(cycle, n)] = ds[q].values
        data["simulated_" + q] = (("case", "cycle"), sim, {
            "units": units, "long_name": "simulated " + long_name + " (2D biaxial rig)"})
    attrs = {k: v for k, v in measured.attrs.items()
             if k not in ("title", "history")}
    # the stress mapping the cases ran under (scenario.mapping): the same for all of them
    attrs.update({k: v for k, v in cases[0].attrs.items() if k.startswith("stress_mapping")}
                 or {"stress_mapping": "none"})
    attrs.update({
        "Conventions": "CF-1.8",
        "title": "measured cyclic test and its simulated biaxial cases",
        "simulated_cases": ", ".join(str(p) for p in case_paths),
        "simulated_seeds": ", ".join(str(ds.attrs.get("seed", "")) for ds in cases),
        "simulated_failures": "; ".join(f"case {k}: {ds.attrs['failure']}" for k, ds in enumerate(cases)
                                        if ds.attrs.get("failed")) or "none",
        "comparison_note": "simulated cycle k (0-based) is plotted at N = k + 1 (cycle 0 is "
                           "the first loading to p + q_max and unloading, as N = 1 of the test); simulated "
                           "strains are 2D (volumetric = area strain) from the end of "
                           "consolidation; measured from the start of the test"})
    return xr.Dataset(data, coords={
        "cycle": ("cycle", cycle, {"units": "1", "long_name": "load cycle number N"}),
        "case": ("case", np.arange(len(cases)), {"units": "1", "long_name": "simulated case"})},
        attrs=attrs)


def plot_comparison(ds, path, title=""):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), dpi=110)
    n = ds["cycle"].values
    for ax, q in zip(axes, QUANTITIES):
        m = ds.get("measured_" + q)
        if m is not None:
            ok = np.isfinite(m.values)
            ax.plot(n[ok], 100 * m.values[ok], "ko", ms=3, label="measured")
        for k in range(ds.sizes["case"]):
            s = ds["simulated_" + q].values[k]
            ok = np.isfinite(s)
            ax.plot(n[ok], 100 * s[ok], "-", lw=1.2, label=f"simulated case {k}")
        ax.set_xscale("log")
        ax.set_xlabel("load cycles N")
        ax.set_ylabel(q.replace("_", " ") + " [%]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
    return path


def write_comparison(measured_path, case_paths, out, figure=None):
    ds = compare_dataset(measured_path, case_paths)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp)
    if figure:
        cond = ", ".join(f"{k} {ds.attrs[k]:g}" for k in ("confining_pressure_kPa",
                         "deviator_max_kPa", "frequency_Hz") if k in ds.attrs)
        failed = ds.attrs["simulated_failures"].count("case ")
        note = f"; {failed} of {ds.sizes['case']} cases failed (attribute simulated_failures)" if failed else ""
        if ds.attrs["stress_mapping"] != "none":
            note += (f"\n2D specimens loaded at q {ds.attrs['stress_mapping_deviator_min_kPa']:.4g}-"
                     f"{ds.attrs['stress_mapping_deviator_max_kPa']:.4g} kPa (stress mapping "
                     f"{ds.attrs['stress_mapping']}, r = {ds.attrs['stress_mapping_ratio']:.3f})")
        else:
            note += "; stress mapping none"
        plot_comparison(ds, figure, f"{ds.attrs.get('source', '')[:90]}\n{cond}{note}")
    return ds
