"""curves.png: per test, the measured points against the plain model and the chosen effect,
in the DEM horizon and extrapolated by each long-term law."""
import numpy as np

from ..atomic import atomic_path
from ..metrics.output import display_scale
from .accumulation import predict
from .statistics import LONG_TERM_LAWS

FAR_CYCLES = 5e5          # how far the long-term laws are drawn (log axis)


def plot_curves(path, run, stats):
    """Write curves.png from an outcome.LoopRun and its statistics.LoopStatistics."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = run.targets.names
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.2 * rows), dpi=100, squeeze=False)
    for j, ax in enumerate(axes.flat):
        if j >= len(names):
            ax.axis("off")
            continue
        _panel(ax, j, run, stats)
        ax.set_title(names[j], fontsize=8)
    axes.flat[0].legend(fontsize=6)
    fig.suptitle("measured vs model: DEM horizon (solid, band = min-max of the cases), extrapolated by "
                 "Sato (dashed) and shakedown (dotted)", fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)


def _panel(ax, j, run, stats):
    """Test j: each model's ensemble (mean, min-max band, long-term laws), the measured points."""
    scale, unit = display_scale(run.settings["quantity"])
    far = np.geomspace(run.settings["cycles"], FAR_CYCLES, 60)
    for label, ens, lt, colour in (("plain", run.plain.runs, stats.long_term, "0.4"),
                                    ("chosen effect", run.selection.after, stats.long_term_after, "C0")):
        if ens is None:
            continue
        c = scale * ens["curves"][j]
        ax.plot(run.cycles, c.mean(axis=0), color=colour, lw=2, label=label)
        ax.fill_between(run.cycles, c.min(axis=0), c.max(axis=0), color=colour, alpha=0.2)
        for law, style in zip(LONG_TERM_LAWS, ("--", ":")):
            if lt[j].fits[law] is not None:
                ax.plot(far, scale * predict(lt[j].fits[law], far)[0], color=colour, ls=style, lw=1)
    n, v = run.targets.points[j]
    ax.plot(n, scale * v, "ko", ms=3, label="measured (DEM horizon)")
    ax.plot(stats.long_term[j].n, scale * stats.long_term[j].measured, "o", mfc="none", mec="k", ms=3,
            label="measured (long-term)")
    ax.set_xscale("log")
    ax.set_xlabel("N")
    ax.set_ylabel(f"{run.settings['quantity'].replace('_', ' ')} [{unit}]")
    ax.grid(alpha=0.3)
