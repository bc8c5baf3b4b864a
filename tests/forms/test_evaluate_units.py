"""`forms evaluate`: the --units of the file's coordinates (mm by default) carried into the
output keys, a warning when a stone's size suggests the wrong unit, and one clear error line
for a file that is not an STL, an open or non-finite mesh, or a bad --density/--units."""

import json

import numpy as np
import pytest
import trimesh

from ballaststudy.cli import main

EDGE_MM = 40.0
DENSITY = 2700.0


def _cube(path, edge, inward=False, **export):
    """A randomly rotated cube of the given edge; random rotation avoids ties between the
    four equally long space diagonals."""
    cube = trimesh.creation.box(extents=(edge, edge, edge))
    cube.apply_transform(trimesh.transformations.random_rotation_matrix(np.random.default_rng(3).random(3)))
    if inward:
        cube = trimesh.Trimesh(cube.vertices, cube.faces[:, ::-1], process=False)
    cube.export(path, **export)
    return path


def _run(capsys, *args):
    rc = main(["forms", "evaluate", *map(str, args)])
    cap = capsys.readouterr()
    return rc, cap.out, cap.err


def _message(err, name):
    """The error text after the file's name (the tmp_path folder is named after the test)."""
    assert f"{name}: " in err, f"stderr {err!r} does not name {name}"
    return err.split(f"{name}: ", 1)[1]


def _cube_expected(s, unit):
    # thesis 3.2 on a cube: a = space diagonal; along it the cube projects to a regular hexagon
    # of circumradius s sqrt(2/3), so b = its long diagonal and c = its width across flats
    return {f"a_{unit}": s * np.sqrt(3), f"b_{unit}": s * np.sqrt(8 / 3), f"c_{unit}": s * np.sqrt(2),
            f"volume_{unit}3": s**3, "mass_kg": DENSITY * (EDGE_MM * 1e-3) ** 3, "a_over_c": np.sqrt(1.5)}


def _assert_close(got, expected):
    # the rotated corners are rounded to float32 in the STL: relative 1e-6
    for k, v in expected.items():
        assert abs(got[k] - v) <= 1e-6 * v, f"{k}: measured {got[k]!r}, expected {v!r}"


@pytest.mark.parametrize("export", [{}, {"file_type": "stl_ascii"}], ids=["binary", "ascii"])
def test_mm_cube_with_default_units(tmp_path, capsys, export):
    path = _cube(tmp_path / "cube_mm.stl", EDGE_MM, **export)
    rc, out, err = _run(capsys, path, "--density", DENSITY)
    assert rc == 0 and err == "", err
    got = json.loads(out)
    assert got["units"] == "mm"
    assert not any(k.endswith(("_m", "_m3")) for k in got), f"metre keys in a mm result: {sorted(got)}"
    _assert_close(got, _cube_expected(EDGE_MM, "mm"))
    # b = 65.3 mm: group 63/80, grid slot 40 mm; c = 56.6 mm >= 40 mm: not flat
    assert got["sieve_group_mm"] == "63/80"
    assert got["grid_slot_width_mm"] == pytest.approx(40.0, rel=1e-12)
    assert (got["flat"], got["non_cubic"], got["long"]) == (False, False, False)


def test_same_cube_in_metres_gives_the_same_stone(tmp_path, capsys):
    rc, out_mm, _ = _run(capsys, _cube(tmp_path / "mm.stl", EDGE_MM), "--density", DENSITY)
    rc_m, out_m, err = _run(capsys, _cube(tmp_path / "m.stl", EDGE_MM * 1e-3), "--density", DENSITY,
                            "--units", "m")
    assert rc == rc_m == 0 and err == "", err
    mm, m = json.loads(out_mm), json.loads(out_m)
    assert m["units"] == "m"
    _assert_close(m, _cube_expected(EDGE_MM * 1e-3, "m"))
    for key_m, key_mm, factor in (("a_m", "a_mm", 1e-3), ("b_m", "b_mm", 1e-3), ("c_m", "c_mm", 1e-3),
                                  ("volume_m3", "volume_mm3", 1e-9),
                                  ("grid_slot_width_m", "grid_slot_width_mm", 1e-3)):
        assert m[key_m] == pytest.approx(mm[key_mm] * factor, rel=1e-6), key_m
    for key in ("mass_kg", "a_over_c"):
        assert m[key] == pytest.approx(mm[key], rel=1e-6)
    for key in ("sieve_group_mm", "flat", "non_cubic", "long"):
        assert m[key] == mm[key], key


@pytest.mark.parametrize("edge, units, shown", [(EDGE_MM, "m", "a = 69.28 m"),
                                                (EDGE_MM * 1e-3, "mm", "a = 0.06928 mm")],
                         ids=["mm_file_read_as_m", "m_file_read_as_mm"])
def test_implausible_size_warns_but_succeeds(tmp_path, capsys, edge, units, shown):
    path = _cube(tmp_path / "scan.stl", edge)
    rc, out, err = _run(capsys, path, "--units", units)
    assert rc == 0, err
    assert json.loads(out)["units"] == units
    assert len(err.strip().splitlines()) == 1, f"expected one warning line, got {err!r}"
    assert err.startswith("ballaststudy: warning: "), err
    msg = _message(err, "scan.stl")
    for word in (shown, "outside 1 mm to 1 m", "--units", f"read as {units}"):
        assert word in msg, f"stderr {err!r} lacks {word!r}"


def _random_bytes(path):
    path.write_bytes(np.random.default_rng(0).bytes(1000))


def _truncated(path):
    _cube(path, EDGE_MM)
    path.write_bytes(path.read_bytes()[:-30])


def _png(path):
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(200))


NOT_STL = {
    "random_bytes": ("stone.stl", _random_bytes),
    "empty": ("stone.stl", lambda p: p.write_bytes(b"")),
    "text": ("stone.stl", lambda p: p.write_text("x y z\n1 2 3\n4 5 6\n")),
    "solid_without_facets": ("stone.stl", lambda p: p.write_text("solid stone\nendsolid stone\n")),
    "truncated_binary": ("stone.stl", _truncated),
    "png_named_stl": ("stone.stl", _png),
    "png": ("stone.png", _png),
    "directory": ("stone.stl", lambda p: p.mkdir()),
    "missing": ("stone.stl", lambda p: None),
}


@pytest.mark.parametrize("case", NOT_STL)
def test_not_an_stl_file(tmp_path, capsys, case):
    name, make = NOT_STL[case]
    make(tmp_path / name)
    rc, out, err = _run(capsys, tmp_path / name)
    assert rc == 2, f"exit code {rc}, stderr {err!r}"
    assert out == "" and len(err.strip().splitlines()) == 1, f"expected one line, got {err!r}"
    expected = "file not found" if case == "missing" else "not an STL file"
    msg = _message(err, name)
    assert msg.startswith(expected) and "closed" not in msg, err


def test_binary_stl_whose_header_starts_with_solid(tmp_path, capsys):
    # some exporters write 'solid' into the binary header: the facet count decides
    path = _cube(tmp_path / "cube.stl", EDGE_MM)
    data = path.read_bytes()
    path.write_bytes(b"solid cube".ljust(80, b" ") + data[80:])
    rc, out, err = _run(capsys, path)
    assert rc == 0, err
    assert json.loads(out)["a_mm"] == pytest.approx(EDGE_MM * np.sqrt(3), rel=1e-6)


def test_open_mesh_is_not_closed(tmp_path, capsys):
    box = trimesh.creation.box(extents=(50, 40, 30))
    path = tmp_path / "open.stl"
    trimesh.Trimesh(box.vertices, box.faces[1:], process=False).export(path)
    rc, out, err = _run(capsys, path)
    assert rc == 2 and out == ""
    assert _message(err, "open.stl").startswith("not a closed mesh"), err


# numpy's warnings on the NaN facets' normals would be stderr lines before the one error line
@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_vertices(tmp_path, capsys, bad):
    box = trimesh.creation.box(extents=(50, 40, 30))
    vertices = box.vertices.copy()
    vertices[0] = (bad, 0, 0)     # inf * 0 in the loader's normals: numpy warns
    path = tmp_path / "nan.stl"
    with np.errstate(invalid="ignore"):
        trimesh.Trimesh(vertices, box.faces, process=False).export(path)
    rc, out, err = _run(capsys, path)
    assert rc == 2 and out == ""
    assert len(err.strip().splitlines()) == 1, err
    msg = _message(err, "nan.stl")
    assert "NaN or infinite" in msg and "must be finite" in msg and "closed" not in msg, err


@pytest.mark.parametrize("density", ["0", "-2650", "nan", "inf", "heavy"])
def test_bad_density(tmp_path, capsys, density):
    rc, out, err = _run(capsys, _cube(tmp_path / "cube.stl", EDGE_MM), "--density", density)
    assert rc == 2 and out == ""
    assert len(err.strip().splitlines()) == 1, err
    assert "--density" in err and "> 0" in err and "finite" in err and density in err, err


def test_bad_units(tmp_path, capsys):
    rc, out, err = _run(capsys, _cube(tmp_path / "cube.stl", EDGE_MM), "--units", "cm")
    assert rc == 2 and out == ""
    assert len(err.strip().splitlines()) == 1, err
    assert "--units" in err and "mm, m" in err and "'cm'" in err, err

