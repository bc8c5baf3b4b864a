"""Everything a finished loading run writes: metrics.nc, the case figure like thesis
Fig. 4-18 (stones by material, breakages marked) and the behaviour curves like Fig. 4-19."""
from pathlib import Path

import numpy as np

from ..atomic import atomic_path
from .records import breakage_records, write_metrics


def plot_case(rig, path, breakages=None, title=""):
    """Stones coloured by material (black hard, grey soft, as Fig. 4-12/4-18), plate and
    loading ball in blue, broken bonds marked (x tension, + shear)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PatchCollection
    from matplotlib.patches import Circle

    sim = rig.sim
    b = sim.balls
    live = np.nonzero(b.alive == 1)[0]
    colour = {0: "0.15", 1: "0.6", 2: "tab:blue"}
    fig, ax = plt.subplots(figsize=(7, 5.2), dpi=120)
    circles = [Circle(b.pos[i], b.rad[i]) for i in live]
    ax.add_collection(PatchCollection(circles, facecolors=[colour.get(int(b.mat[i]), "k") for i in live],
                                      edgecolors="none"))
    seg = sim.walls.seg
    keep = np.zeros(len(seg), bool)
    for ids in rig.wall_groups().values():
        keep[ids] = True
    ax.add_collection(LineCollection(seg[keep].reshape(-1, 2, 2), colors="k", linewidths=1.5))
    if breakages is not None and len(breakages["x"]):
        t = breakages["mode_code"] == 1
        ax.plot(breakages["x"][t], breakages["y"][t], "x", color="red", ms=7, mew=2,
                label=f"tension ({int(t.sum())})")
        ax.plot(breakages["x"][~t], breakages["y"][~t], "+", color="orange", ms=8, mew=2,
                label=f"shear ({int((~t).sum())})")
        ax.legend(loc="upper right", fontsize=8)
    w2 = 0.5 * rig.params.width_m
    ax.set_xlim(-w2 - 0.01, w2 + 0.01)
    ax.set_ylim(-0.01, rig.params.height_m + 0.03)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or "box test: black hard, grey soft rock; breakages marked")
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)
    return path


def plot_behaviours(ds, path):
    """Behaviour curves over the cycles (Fig. 4-19): whatever behaviours ds holds."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [n for n in ("settlement", "axial_strain", "volumetric_strain", "breakage_rate",
                         "breakage_rate_tension", "breakage_rate_shear", "fpa", "void_ratio",
                         "ghost_particles") if n in ds]
    fig, axes = plt.subplots(len(names), 1, figsize=(6, 1.9 * len(names)), sharex=True, dpi=110)
    axes = np.atleast_1d(axes)
    for ax, n in zip(axes, names):
        v = ds[n]
        scale, unit = (1e3, "mm") if v.attrs.get("units") == "m" else (1.0, v.attrs.get("units", ""))
        ax.plot(ds["cycle"], v * scale, lw=1.2)
        ax.set_ylabel(f"{n} [{unit}]", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("loading cycle")
    fig.suptitle(f"{ds.attrs.get('database', '')}: behaviours under cyclic loading", fontsize=9)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)
    return path


def write_figures(run, ds, out, what=""):
    """case.png and behaviours.png beside ``out`` (any rig)."""
    out = Path(out)
    plot_case(run.rig, out.with_name("case.png"), breakage_records(run),
              title=f"{ds.attrs['database']} seed {ds.attrs['seed']}: {what}after "
                    f"{ds.sizes['cycle']} cycles (black hard, grey soft)")
    if ds.sizes["cycle"]:       # a specimen that failed in its first loading has no curve
        plot_behaviours(ds, out.with_name("behaviours.png"))


def write_outputs(run, out, figures=True, attrs=None):
    """metrics.nc of a box run (+ figures beside it). Returns the dataset."""
    ds = write_metrics(run, Path(out), attrs)
    if figures:
        write_figures(run, ds, out)
    return ds
