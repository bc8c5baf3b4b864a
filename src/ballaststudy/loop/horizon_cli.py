"""`ballaststudy horizon`: the long-term horizon's extrapolation table from measured curves
(loop/horizon.py) -> horizon.nc, horizon.md and horizon.png in one folder.

    ballaststudy horizon results/measured/<t1>.nc ... --out-dir results/horizon
        [--fit-cycles 1000 10000] [--quantity axial_strain]"""
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from ..argtypes import add_quiet, number
from ..inputs import writable_dir
from ..measured.importer import measured_test_name
from ..metrics.output import display_scale
from .accumulation import LAWS, fit_law
from .horizon import STATED_QUANTILE, horizon_table, measured_curve

LAW_FORMS = {"sato": "eps0 + gamma (1 - e^(-alpha (N-1))) + beta (N-1)",
             "shakedown": "eps0 + gamma (1 - e^(-alpha (N-1)))",
             "hardening_log": "eps0 + gamma (1 - e^(-alpha (N-1))) + c ln N",
             "log": "a + b ln N", "power": "a N^b"}


def horizon_markdown(ds):
    """horizon.md: the summary per law and N_fit, the chosen law, then every curve's errors."""
    scale, unit = display_scale(ds.attrs["quantity"])
    fits = ds["fit_cycles"].values
    lines = ["# Long-term horizon: how far each accumulation law carries a measured curve", "",
             f"Each law fitted to a measured {ds.attrs['quantity'].replace('_', ' ')} curve on its points up to "
             "N_fit, then read at the curve's last point (up to ~5e5 cycles); error = predicted - measured, in "
             f"{unit}. A curve enters an N_fit with a point beyond it and more points up to it than any law has "
             "parameters; a law that cannot be fitted to an entered curve counts as an infinite error. Chosen: "
             f"the smallest median |error|; its {STATED_QUANTILE:g} quantile is the uncertainty the loop states.",
             "", "| law | form | " + " | ".join(f"N_fit {f:g}: median / {STATED_QUANTILE:g} quantile |error|, fitted"
                                                for f in fits) + " |",
             "|---|---|" + "---|" * len(fits)]
    for law in ds["law"].values:
        cells = [f"{_num(scale * ds['median_abs_error'].sel(law=law).values[k])} / "
                 f"{_num(scale * ds['stated_abs_error'].sel(law=law).values[k])}, "
                 f"{int(ds['curves_fitted'].sel(law=law).values[k])} of {int(ds['curves_entered'].values[k])}"
                 for k in range(len(fits))]
        lines.append(f"| {law} | {LAW_FORMS[law]} | " + " | ".join(cells) + " |")
    lines += [""] + [f"- **N_fit {f:g}: {_chosen(ds, k)}**" for k, f in enumerate(fits)] + ["", "## Per curve", "",
              "| test | last N | measured last | " + " | ".join(f"{law} @ {f:g}" for f in fits for law in ds["law"].values)
              + " |", "|---|---|---|" + "---|" * (len(fits) * ds.sizes["law"])]
    for i, test in enumerate(ds["test"].values):
        cells = [_num(scale * ds["error"].values[i, j, k]) if ds["entered"].values[i, k] else "-"
                 for k in range(len(fits)) for j in range(ds.sizes["law"])]
        lines.append(f"| {test} | {ds['last_cycle'].values[i]:.3g} | {scale * ds['measured_last'].values[i]:.3g} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines + ["", "('-': not entered; 'no fit': the law could not be fitted.)", ""])


def _num(x):
    return f"{x:.3g}" if np.isfinite(x) else "no fit"


def _chosen(ds, k):
    law = str(ds["chosen_law"].values[k])
    if not law:
        return "no curve entered: no law chosen"
    scale, unit = display_scale(ds.attrs["quantity"])
    return (f"{law}, median |error| {scale * float(ds['median_abs_error'].sel(law=law).values[k]):.3g} {unit}, "
            f"{STATED_QUANTILE:g} quantile {scale * float(ds['stated_abs_error'].sel(law=law).values[k]):.3g} {unit} "
            f"over {int(ds['curves_entered'].values[k])} curves")


def plot_horizon(path, ds, curves):
    """horizon.png: each entered curve with every N_fit's chosen law drawn from N_fit on."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [t for t in ds["test"].values if ds["entered"].sel(test=t).values.any()] or list(ds["test"].values)[:1]
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    scale, unit = display_scale(ds.attrs["quantity"])
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols, 2.8 * rows), dpi=90, squeeze=False)
    for ax, name in zip(axes.flat, names):
        n, v = curves[name]
        ax.plot(n, scale * v, "ko", ms=3)
        for k, fc in enumerate(ds["fit_cycles"].values):
            law = str(ds["chosen_law"].values[k])
            if law and ds["entered"].sel(test=name).values[k]:
                fit = fit_law(law, n[n <= fc], v[n <= fc])
                far = np.geomspace(1.0, n.max(), 80)
                ax.plot(far, scale * LAWS[law](far, fit.params), color=f"C{k}", lw=1, label=f"{law} fitted to N <= {fc:g}")
                ax.axvline(fc, color=f"C{k}", lw=0.5, ls=":")
        ax.set_xscale("log")
        ax.set_ylim(0, 1.3 * scale * v.max())    # the measured range: an extrapolation never sets the scale
        ax.set_title(name, fontsize=7)
        ax.set_xlabel("N")
        ax.set_ylabel(f"[{unit}]")
        ax.grid(alpha=0.3)
    axes.flat[0].legend(fontsize=6)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)


def _horizon(args):
    out = writable_dir(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    curves = {measured_test_name(p): measured_curve(p, args.quantity) for p in args.measured}
    ds = horizon_table(curves, sorted(args.fit_cycles), args.quantity)
    with atomic_path(out / "horizon.nc") as tmp:
        ds.to_netcdf(tmp)
    plot_horizon(out / "horizon.png", ds, curves)
    with atomic_path(out / "horizon.md") as tmp:
        tmp.write_text(horizon_markdown(ds))
    if not args.quiet:
        print("\n".join(f"N_fit {f:g}: {_chosen(ds, k)}" for k, f in enumerate(ds["fit_cycles"].values)))


def register(subparsers):
    c = subparsers.add_parser("horizon", help="each accumulation law's extrapolation error on measured "
                              "curves; the law the loop's long-term horizon uses")
    c.add_argument("measured", nargs="+", type=Path, help="measured tests' netCDF (measured import)")
    c.add_argument("--out-dir", type=Path, required=True, help="folder for horizon.nc, horizon.md and horizon.png")
    c.add_argument("--fit-cycles", type=number(1, 1e7), nargs="+", default=[1000.0, 10000.0],
                   help="N_fit: each law sees the points up to this load cycle")
    c.add_argument("--quantity", choices=["axial_strain", "volumetric_strain"], default="axial_strain",
                   help="the measured curve the laws are fitted to")
    add_quiet(c)
    c.set_defaults(func=_horizon)
    return c
