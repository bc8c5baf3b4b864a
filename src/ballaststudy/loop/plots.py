"""curves.png: per test, the measured points against the plain model and the chosen effect,
in the DEM horizon and extrapolated by the long-term law with its stated error."""
import numpy as np

from ..atomic import atomic_path
from ..metrics.output import display_scale
from .accumulation import predict

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
    law = run.long_term_law
    fig.suptitle("measured vs model: DEM horizon (solid, band = min-max of the cases)"
                 + (f", extrapolated by the {law.name} law (dashed, band = its error on measured curves)" if law else
                    "; no long-term law given"), fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    plt.close(fig)


def _panel(ax, j, run, stats):
    """Test j: each model's ensemble (mean, min-max band, long-term laws), the measured points."""
    scale, unit = display_scale(run.settings["quantity"])
    far = np.geomspace(run.settings["cycles"], FAR_CYCLES, 60)
    top, low = [], [0.0]
    for label, ens, lt, colour in (("plain", run.plain.runs, stats.long_term, "0.4"),
                                    ("chosen effect", run.selection.after, stats.long_term_after, "C0")):
        if ens is None:
            continue
        c = scale * ens["curves"][j]
        ax.plot(run.cycles, c.mean(axis=0), color=colour, lw=2, label=label)
        ax.fill_between(run.cycles, c.min(axis=0), c.max(axis=0), color=colour, alpha=0.2)
        top.append(c.max())
        low.append(c.min())
        if lt is not None and lt[j].fit is not None:
            line = scale * predict(lt[j].fit, far)[0]
            ax.plot(far, line, color=colour, ls="--", lw=1)
            band = scale * run.long_term_law.stated_error
            ax.fill_between(far, line - band, line + band, color=colour, alpha=0.08)
    n, v = run.targets.points[j]
    top += [scale * v.max(initial=0.0), scale * stats.long_term[j].measured.max(initial=0.0)]
    low += [scale * v.min(initial=0.0), scale * stats.long_term[j].measured.min(initial=0.0)]
    ax.plot(n, scale * v, "ko", ms=3, label="measured (DEM horizon)")
    ax.plot(stats.long_term[j].n, scale * stats.long_term[j].measured, "o", mfc="none", mec="k", ms=3,
            label="measured (long-term)")
    # what was measured and simulated sets the scale: an extrapolation never squeezes them flat
    span = max(top) - min(low)
    ax.set_ylim(min(low) - 0.05 * span, max(top) + 0.3 * span if span > 0 else None)
    ax.set_xscale("log")
    ax.set_xlabel("N")
    ax.set_ylabel(f"{run.settings['quantity'].replace('_', ' ')} [{unit}]")
    ax.grid(alpha=0.3)
