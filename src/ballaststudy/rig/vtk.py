"""VTK XML PolyData (.vtp, ASCII) snapshots for ParaView, written by hand (no dependency).

* ``balls_NNNN.vtp``: one vertex per live ball with point data radius, stone, fragment,
  material (0 hard, 1 soft, 2 steel), body (0 stone, 1 plate, 2 loading ball);
  show with the "Point Gaussian" representation scaled by ``radius``.
* ``bonds_NNNN.vtp``: one line per flat joint (rigid stones: the joints they were
  assembled with) with cell data state (0 intact - for rigid stones: inside one clump -,
  1 broken in tension, 2 broken in shear, 3 partly broken).
* ``walls_NNNN.vtp``: the wall segments with cell data kind and force.
"""
from pathlib import Path

import numpy as np

from ..atomic import atomic_path


def _arr(name, a, kind):
    if kind == "Float64":
        body = " ".join(f"{v:.9g}" for v in np.ravel(a))
    else:
        body = " ".join(str(int(v)) for v in np.ravel(a))
    ncomp = a.shape[1] if np.ndim(a) == 2 else 1
    return (f'<DataArray type="{kind}" Name="{name}" NumberOfComponents="{ncomp}" '
            f'format="ascii">{body}</DataArray>')


def _polydata(path, points, verts=None, lines=None, point_data=(), cell_data=()):
    pts = np.column_stack([points, np.zeros(len(points))])
    parts = ['<?xml version="1.0"?>',
             '<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">', "<PolyData>"]
    nv = 0 if verts is None else len(verts)
    nl = 0 if lines is None else len(lines)
    parts.append(f'<Piece NumberOfPoints="{len(pts)}" NumberOfVerts="{nv}" NumberOfLines="{nl}" '
                 'NumberOfStrips="0" NumberOfPolys="0">')
    parts.append("<PointData>" + "".join(_arr(n, a, k) for n, a, k in point_data) + "</PointData>")
    parts.append("<CellData>" + "".join(_arr(n, a, k) for n, a, k in cell_data) + "</CellData>")
    parts.append("<Points>" + _arr("Points", pts, "Float64") + "</Points>")
    for tag, conn, per in (("Verts", verts, 1), ("Lines", lines, 2)):
        if conn is not None and len(conn):
            c = np.asarray(conn, np.int64).reshape(-1, per)
            parts.append(f"<{tag}>" + _arr("connectivity", c.ravel(), "Int64")
                         + _arr("offsets", np.arange(1, len(c) + 1) * per, "Int64") + f"</{tag}>")
    parts += ["</Piece>", "</PolyData>", "</VTKFile>"]
    with atomic_path(path) as tmp:
        Path(tmp).write_text("\n".join(parts))
    return path


def write_vtk(rig, folder, tag):
    """Balls, bonds and walls of the rig's current state; returns the three paths."""
    folder = Path(folder)
    sim, lay = rig.sim, rig.layout
    b = sim.balls
    live = np.nonzero(b.alive == 1)[0]
    frag = np.full(len(b), -1)
    frag[: lay.n_stone_balls] = rig.fragments()
    body = np.zeros(len(b), np.int64)          # 0 stones, k: the rig's k-th other body
    for k, ids in enumerate(rig.body_balls().values(), start=1):
        body[ids] = k
    pb = _polydata(folder / f"balls_{tag}.vtp", b.pos[live], verts=np.arange(len(live)),
                   point_data=[("radius", b.rad[live], "Float64"),
                               ("stone", b.stone[live], "Int32"),
                               ("fragment", frag[live], "Int32"),
                               ("material", b.mat[live], "Int32"),
                               ("body", body[live], "Int32")])
    bd = sim.bonds
    _, _, intact = rig.stones.topology(sim)     # the links holding each stone together now
    allint = bd.state.min(axis=1) == 1
    state = np.where(allint, 0, 3)
    br = sim.breakages()
    mode_of = np.zeros(len(bd), np.int64)
    kept = br["bond"] >= 0                      # -1: a deleted ball's bond, taken out
    mode_of[br["bond"][kept]] = np.where(br["mode"][kept] == "tension", 1, 2)
    state = np.where(~intact, mode_of, state)
    keep = (b.alive[bd.i] == 1) & (b.alive[bd.j] == 1)
    idx = {int(v): k for k, v in enumerate(live)}
    lines = np.array([[idx[int(i)], idx[int(j)]] for i, j in zip(bd.i[keep], bd.j[keep])],
                     np.int64).reshape(-1, 2)
    pf = _polydata(folder / f"bonds_{tag}.vtp", b.pos[live], lines=lines,
                   cell_data=[("state", state[keep], "Int32")])
    seg = sim.walls.seg
    kind = np.zeros(len(seg), np.int64)         # 0 other, k: the rig's k-th wall group
    for k, ids in enumerate(rig.wall_groups().values(), start=1):
        kind[ids] = k
    pts = seg.reshape(-1, 2)
    pw = _polydata(folder / f"walls_{tag}.vtp", pts, lines=np.arange(len(pts)).reshape(-1, 2),
                   cell_data=[("kind", kind, "Int32"), ("force", sim.walls.force, "Float64")])
    return pb, pf, pw


def vtk_hook(folder, cycles, total):
    """End-of-cycle hook writing VTK at the chosen cycles (negative = from the end)."""
    want = {c if c >= 0 else total + c for c in cycles}

    def hook(run, cycle):
        if cycle in want:
            write_vtk(run.rig, folder, f"cycle{cycle:05d}")
    return hook
