"""Validation report of form databases: the table and figures of thesis 3.5 (Figs. 3-9 ... 3-16).

Databases are grouped by name: G_<group>-<index> belongs to group <group>; any other name
(e.g. box_test) is a group of its own. Figures list databases by group, then index."""

import re
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ..atomic import atomic_path
from ..standards import GRADING_SIEVES_MM
from .database import stone_meshes
from .validate import validation_row

DPI = 130
_NAME = re.compile(r"G_(\d+)-(\d+)$")
_GRADING_FIGURES = {1: ("fig_3-10_grading_group1.png", "group 1: varying mean sizes"),
                    2: ("fig_3-11_grading_group2.png", "group 2: varying size distributions"),
                    3: ("fig_3-12_grading_group3.png", "group 3: varying shape index")}
_LIGHT = np.array([0.4, -0.5, 0.77]) / np.linalg.norm([0.4, -0.5, 0.77])
_MATERIAL_RGB = np.array([[0.55, 0.55, 0.6], [0.8, 0.72, 0.55]])  # by material flag, cycled
_OBJ, _GEN, _OBJ_LINE = "#9ecae1", "#08519c", "#e6550d"


def _order_key(name):
    m = _NAME.match(name)
    return (0, int(m[1]), int(m[2]), "") if m else (1, 0, 0, name)


def _group(name):
    m = _NAME.match(name)
    return int(m[1]) if m else name


def _new_figure(figsize):
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path):
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)
    return Path(path)


def write_report(datasets, out_dir, n_stones=9, seed=0):
    """Write validation.csv and the figures like thesis Figs. 3-9 ... 3-16 into `out_dir`
    (atomically); return the written paths. `datasets`: loaded form databases (any order)."""
    if not datasets:
        raise ValueError("write_report: no datasets")
    if n_stones < 1:
        raise ValueError(f"write_report: n_stones must be >= 1, got {n_stones}")
    out = Path(out_dir)
    datasets = sorted(datasets, key=lambda ds: _order_key(ds.attrs["database"]))
    table = pd.DataFrame([validation_row(ds) for ds in datasets])
    paths = [write_validation_csv(table, out / "validation.csv"),
             _save(fig_stones(datasets, n_stones, seed), out / "fig_3-9_stones.png")]
    for group, rows in table.groupby(table.database.map(_group), sort=False):
        name, title = _GRADING_FIGURES.get(group, (f"fig_grading_{group}.png", str(group)))
        paths.append(_save(fig_grading(rows, title), out / name))
    paths.append(_save(fig_particle_numbers(table), out / "fig_3-13_particle_numbers.png"))
    paths.append(_save(fig_mass(table), out / "fig_3-14_mass.png"))
    paths.append(_save(fig_shape_index(table), out / "fig_3-15_shape_index.png"))
    paths.append(_save(fig_particle_length(table), out / "fig_3-16_particle_length.png"))
    return paths


def write_validation_csv(table, path):
    """All columns of `validation_row`, one row per database (the numbers behind Figs. 3-10 ... 3-16)."""
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False)
    return Path(path)


def _draw_stone(ax, mesh, material, label):
    verts = np.asarray(mesh.vertices) * 1e3
    shade = 0.35 + 0.65 * np.clip(mesh.face_normals @ _LIGHT, 0.0, 1.0)
    colors = _MATERIAL_RGB[material % len(_MATERIAL_RGB)] * shade[:, None]
    ax.add_collection3d(Poly3DCollection(verts[mesh.faces], facecolors=colors, edgecolors="k",
                                         linewidths=0.2))
    r = np.abs(verts).max()
    ax.set(xlim=(-r, r), ylim=(-r, r), zlim=(-r, r))
    ax.set_box_aspect((1, 1, 1))
    ax.set_axis_off()
    ax.set_title(label, fontsize=6)


def fig_stones(datasets, n_stones, seed):
    """Fig. 3-9: `n_stones` random stones per database (rng = default_rng(seed) for each
    database, so a database shows the same stones whatever else is in the report)."""
    fig = _new_figure((max(1.5 * n_stones + 0.6, 5.0), 1.7 * len(datasets) + 1.3))
    for row, ds in enumerate(datasets):
        n = ds.sizes["stone"]
        picked = np.sort(np.random.default_rng(seed).choice(n, size=min(n_stones, n), replace=False))
        meshes = stone_meshes(ds)
        for col, i in enumerate(picked):
            ax = fig.add_subplot(len(datasets), n_stones, row * n_stones + col + 1, projection="3d")
            dims = "/".join(f"{1e3 * float(ds[k][i]):.0f}" for k in "abc")
            _draw_stone(ax, meshes[i], int(ds.material[i]), f"#{i}: a/b/c = {dims} mm")
            if col == 0:
                ax.text2D(-0.12, 0.5, ds.attrs["database"], transform=ax.transAxes, rotation=90,
                          va="center", ha="center", fontsize=9, fontweight="bold")
    fig.suptitle(f"Form databases\n{n_stones} random stones each (seed {seed}), a/b/c in mm", fontsize=11)
    materials = datasets[0].material.attrs["flag_meanings"].split()
    fig.legend(handles=[Patch(color=_MATERIAL_RGB[k % len(_MATERIAL_RGB)], label=f"{m} rock")
                        for k, m in enumerate(materials)], loc="lower center", fontsize=8, ncols=2)
    width, height = fig.get_size_inches()
    fig.subplots_adjust(left=0.45 / width, right=0.99, bottom=0.4 / height, top=1 - 0.9 / height,
                        wspace=0.05, hspace=0.25)
    return fig


def fig_grading(rows, title):
    """Figs. 3-10 (group 1), 3-11 (group 2), 3-12 (group 3), or another group's (e.g. box_test)
    grading: objective (dashed) vs generated (solid, markers), one panel per database."""
    ncols = min(len(rows), 3)
    nrows = -(-len(rows) // ncols)
    fig = _new_figure((max(4.2 * ncols, 5.5), 3.4 * nrows + 0.6))
    sieves = np.array(GRADING_SIEVES_MM)
    for k, (_, r) in enumerate(rows.iterrows()):
        ax = fig.add_subplot(nrows, ncols, k + 1)
        ax.plot(sieves, [r[f"passing_{s:g}mm_pct"] for s in sieves], "-o", color=_GEN, ms=4,
                label="generated")
        ax.plot(sieves, [r[f"objective_passing_{s:g}mm_pct"] for s in sieves], "--", color=_OBJ_LINE,
                lw=1.5, label="objective")
        ax.set_xscale("log")
        ax.set_xticks(sieves, [f"{s:g}" for s in sieves], fontsize=7)
        ax.minorticks_off()
        ax.set(xlabel="sieve size (mm)", ylabel="percent passing by mass (%)", ylim=(-2, 102),
               title=r.database)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    fig.suptitle(f"Grading of the objective and generated aggregate\n({title})")
    fig.tight_layout()
    return fig


def _bar_axes(table):
    fig = _new_figure((max(5.0, 0.7 * len(table) + 2), 4.2))
    ax = fig.add_subplot()
    ax.set_xticks(np.arange(len(table)), table.database, rotation=45, ha="right")
    ax.grid(axis="y", alpha=0.3)
    return fig, ax


def _paired_bars(table, objective, generated, ylabel, title, fmt):
    fig, ax = _bar_axes(table)
    x = np.arange(len(table))
    for dx, col, color, label in ((-0.2, objective, _OBJ, "objective"), (0.2, generated, _GEN, "generated")):
        bars = ax.bar(x + dx, table[col].astype(float), 0.4, color=color, label=label)
        ax.bar_label(bars, fmt=fmt, fontsize=6, rotation=90, padding=2)
    ax.set_ylim(0, 1.25 * table[[objective, generated]].astype(float).to_numpy().max())
    ax.set(ylabel=ylabel, title=title)
    ax.legend(fontsize=8, ncols=2, loc="upper center")
    fig.tight_layout()
    return fig


def fig_particle_numbers(table):
    """Fig. 3-13: number of generated particles per database."""
    fig, ax = _bar_axes(table)
    bars = ax.bar(np.arange(len(table)), table.particle_count, 0.6, color=_GEN)
    ax.bar_label(bars, fontsize=7)
    ax.set_ylim(0, 1.12 * table.particle_count.max())
    ax.set(ylabel="number of particles (-)", title="Particle numbers")
    fig.tight_layout()
    return fig


def fig_mass(table):
    """Fig. 3-14: objective vs generated total mass."""
    return _paired_bars(table, "objective_mass_kg", "total_mass_kg", "total mass (kg)", "Total mass", "%.2f")


def fig_shape_index(table):
    """Fig. 3-15: objective vs generated shape index SI (EN 13450)."""
    return _paired_bars(table, "objective_si_pct", "si_pct", "shape index SI (%)", "Shape index", "%.1f")


def fig_particle_length(table):
    """Fig. 3-16: objective vs generated particle length index LI (EN 13450)."""
    return _paired_bars(table, "objective_li_pct", "li_pct", "particle length index LI (%)",
                        "Particle length index", "%.2f")
