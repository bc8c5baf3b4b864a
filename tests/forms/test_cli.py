"""The `ballaststudy` command for the forms stage: bad input gives one clear line naming file,
key and allowed range, exit code 2 and no output files; `forms evaluate` and
`forms validate --json` on good input."""

import json
import re

import numpy as np
import pytest
import trimesh
import yaml

from ballaststudy.cli import main

MATERIALS = {"hard": {"mass_fraction": 0.7, "density_kg_m3": 2850},
             "soft": {"mass_fraction": 0.3, "density_kg_m3": 2620}}
GOOD = {"mass_kg": 5, "grading": "G_CRB B", "shape_index": 30, "particle_length_index": 0,
        "materials": MATERIALS}


def _write_config(tmp_path, databases, forms=None, selected="all"):
    db_file = tmp_path / "my_databases.yaml"
    db_file.write_text(yaml.safe_dump({"databases": databases}, sort_keys=False))
    cfg = tmp_path / "my_config.yaml"
    cfg.write_text(yaml.safe_dump({"seed": 7, "databases_file": str(db_file), "databases": selected,
                                   "forms": forms or {}}))
    return cfg, db_file


def _assert_no_outputs(out):
    if not out.exists():
        return
    bad = [p.name for p in out.iterdir()
           if p.name.endswith((".nc", ".zip", ".json")) or ".tmp" in p.name]
    assert not bad, f"output folder holds {bad} after a failed run"


def _generate(tmp_path, capsys, databases, args=("--all",), forms=None, selected="all"):
    cfg, db_file = _write_config(tmp_path, databases, forms, selected)
    out = tmp_path / "out"
    out.mkdir()
    rc = main(["forms", "generate", *args, "--out", str(out), "--config", str(cfg), "--quiet"])
    err = capsys.readouterr().err
    return rc, err, out, cfg, db_file


# the allowed range, however phrased: "0-100", "0 to 100", ">= 0 and <= 100"
RANGE_0_100 = r"\b0\s*(-|–|to)\s*100\b|>=\s*0\s*and\s*<=\s*100"


@pytest.mark.parametrize("override, key", [
    pytest.param({"grading": [100, 101, 90, 50, 20, 5, 0, 0]}, "databases.bad.grading", id="above_100"),
    pytest.param({"grading": [100, 100, 90, 50, 20, 5, -1, 0]}, "databases.bad.grading", id="below_0"),
    pytest.param({"shape_index": 150}, "databases.bad.shape_index", id="shape_index_150"),
])
def test_percent_passing_outside_0_100(tmp_path, capsys, override, key):
    rc, err, out, _, db_file = _generate(tmp_path, capsys, {"bad": {**GOOD, **override}})
    assert rc == 2, f"exit code {rc}, stderr {err!r}"
    assert db_file.name in err and key in err, f"stderr {err!r} lacks file {db_file.name} or key {key}"
    assert re.search(RANGE_0_100, err), f"stderr {err!r} does not state the allowed range 0-100"
    _assert_no_outputs(out)


@pytest.mark.parametrize("override, key, words", [
    ({"grading": [100, 100, 90, 50, 60, 5, 0, 0]}, "databases.bad.grading[4]", ["increase"]),
    ({"shape_index": 30, "flakiness_index": 20}, "databases.bad.shape_index", ["SI", "FI"]),
    ({"mass_kg": 0}, "databases.bad.mass_kg", ["> 0"]),
    ({"mass_kg": -2.5}, "databases.bad.mass_kg", ["> 0"]),
    ({"shape_index": "SI_RB 7"}, "databases.bad.shape_index",
     ["SI_RB 10", "SI_RB 20", "SI_RB 30", "SI_RB 5/30"]),
    ({"grading": "G_CRB Z"}, "databases.bad.grading", ["G_CRB A", "G_CRB E"]),
    ({"particle_length_index": "L_RB X"}, "databases.bad.particle_length_index", ["L_RB A", "L_RB D"]),
    # nothing above 40 mm: no stone can reach a >= 100 mm at a/b <= 2.5
    ({"grading": [100, 100, 100, 100, 100, 50, 10, 0], "particle_length_index": 5},
     "databases.bad.particle_length_index", ["mm"]),
])
def test_bad_database_definitions(tmp_path, capsys, override, key, words):
    rc, err, out, _, db_file = _generate(tmp_path, capsys, {"ok": GOOD, "bad": {**GOOD, **override}})
    assert rc == 2, f"exit code {rc}, stderr {err!r}"
    assert db_file.name in err, f"stderr {err!r} does not name the file {db_file.name}"
    assert key in err, f"stderr {err!r} does not name the key {key}"
    missing = [w for w in words if w not in err]
    assert not missing, f"stderr {err!r} lacks {missing}"
    assert len(err.strip().splitlines()) == 1, f"expected one line, got {err!r}"
    _assert_no_outputs(out)   # not even the good database is generated


def test_unknown_database_name(tmp_path, capsys):
    rc, err, out, cfg, _ = _generate(tmp_path, capsys, {"ok": GOOD, "also_ok": GOOD}, args=("nope",))
    assert rc == 2
    assert cfg.name in err and "nope" in err, err
    assert "ok" in err and "also_ok" in err, f"allowed names missing in {err!r}"
    _assert_no_outputs(out)


def test_unknown_database_name_in_config(tmp_path, capsys):
    rc, err, out, cfg, _ = _generate(tmp_path, capsys, {"ok": GOOD}, selected=["ok", "nope"])
    assert rc == 2
    assert cfg.name in err and "databases" in err and "nope" in err, err
    _assert_no_outputs(out)


def test_unreachable_shape_index_from_form_params(tmp_path, capsys):
    # a/b <= 1.5 and c/b >= 0.9 give a/c <= 1.67: no stone can be non-cubic (a/c > 3), so an
    # SI objective of 30 % is unreachable and must be an error, not a database with SI 0 %
    rc, err, out, _, _ = _generate(tmp_path, capsys, {"x": GOOD},
                                   forms={"ab_ratio_max": 1.5, "cb_ratio_min": 0.9})
    made = sorted(p.name for p in out.iterdir())
    assert rc == 2, f"exit code {rc} (stderr {err!r}); the run wrote {made}"
    assert "shape_index" in err or "ab_ratio_max" in err, err
    _assert_no_outputs(out)


def test_forms_value_outside_schema_range(tmp_path, capsys):
    rc, err, out, cfg, _ = _generate(tmp_path, capsys, {"x": GOOD}, forms={"n_vertices": 3})
    assert rc == 2
    assert cfg.name in err and "forms.n_vertices" in err and ">= 8" in err and "<= 200" in err, err
    _assert_no_outputs(out)


def test_generate_writes_database_files(tmp_path, capsys):
    # the files the failure tests look for are what a successful run writes
    rc, err, out, _, _ = _generate(tmp_path, capsys, {"ok": {**GOOD, "mass_kg": 3}, "other": GOOD},
                                   args=("ok",))
    assert rc == 0, err
    made = sorted(p.name for p in out.iterdir())
    assert made == ["ok.nc", "ok.nc.prov.json", "ok.stl.zip", "ok.stl.zip.prov.json"], made


def test_good_config_check(tmp_path, capsys):
    cfg, _ = _write_config(tmp_path, {"ok": GOOD, "box": {**GOOD, "flakiness_index": "FI_RB 35"}})
    assert main(["config", "check", "--config", str(cfg)]) == 0
    assert "2 databases: ok, box" in capsys.readouterr().out


# -- forms evaluate -------------------------------------------------------------------------

def test_evaluate_open_stl_is_an_error(tmp_path, capsys):
    box = trimesh.creation.box(extents=(0.05, 0.04, 0.03))
    open_mesh = trimesh.Trimesh(box.vertices, box.faces[1:], process=False)
    assert not open_mesh.is_watertight
    path = tmp_path / "open_stone.stl"
    open_mesh.export(path)
    rc = main(["forms", "evaluate", str(path)])
    cap = capsys.readouterr()
    assert rc == 2, f"exit code {rc}"
    assert "open_stone.stl" in cap.err and "closed" in cap.err, cap.err
    assert cap.out == ""


def test_evaluate_missing_file_is_an_error(tmp_path, capsys):
    rc = main(["forms", "evaluate", str(tmp_path / "absent.stl")])
    assert rc == 2 and "absent.stl" in capsys.readouterr().err


@pytest.mark.parametrize("inward", [False, True])
def test_evaluate_closed_cube(tmp_path, capsys, inward):
    # side 3/64 m: the corners +-3/128 are exact in the STL's float32. a = s sqrt3 = 81.2 mm,
    # b = s sqrt(8/3) = 76.5 mm -> group 63/80, slot 40 mm; c = s sqrt2 = 66.3 mm: not flat;
    # a/c = sqrt(3/2): cubic; a < 100 mm: not long.
    s = 3 / 64
    cube = trimesh.creation.box(extents=(s, s, s))
    cube.apply_transform(trimesh.transformations.random_rotation_matrix(np.random.default_rng(1).random(3)))
    if inward:
        cube = trimesh.Trimesh(cube.vertices, cube.faces[:, ::-1], process=False)
    path = tmp_path / "cube.stl"
    cube.export(path)
    rc = main(["forms", "evaluate", str(path), "--density", "2700", "--units", "m"])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    got = json.loads(cap.out)
    # the rotated corners are rounded to float32 in the STL: relative 1e-6
    assert got["units"] == "m" and cap.err == ""
    expected = {"a_m": s * np.sqrt(3), "b_m": s * np.sqrt(8 / 3), "c_m": s * np.sqrt(2), "volume_m3": s**3,
                "mass_kg": 2700 * s**3, "a_over_c": np.sqrt(1.5)}
    for k, v in expected.items():
        assert abs(got[k] - v) <= 1e-6 * v, f"{k}: measured {got[k]!r}, expected {v!r}"
    assert got["sieve_group_mm"] == "63/80"
    assert got["grid_slot_width_m"] == pytest.approx(0.040, rel=1e-12)
    assert (got["flat"], got["non_cubic"], got["long"]) == (False, False, False)


# -- forms validate -------------------------------------------------------------------------

def test_validate_json(small_database, capsys, tmp_path):
    nc, ds, _ = small_database
    csv = tmp_path / "v.csv"
    rc = main(["forms", "validate", str(nc), "--json", "--csv", str(csv)])
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    rows = json.loads(cap.out)
    assert isinstance(rows, list) and len(rows) == 1
    row = rows[0]
    for key in ("database", "max_sieve_error_pp", "si_error_pp", "li_error_pp", "mass_ratio_pct"):
        assert key in row, f"key {key} missing in {sorted(row)}"
    assert row["database"] == "small"
    assert row["particle_count"] == ds.sizes["stone"]
    assert row["total_mass_kg"] == pytest.approx(float(ds.mass.values.sum()), rel=1e-12)
    assert csv.is_file() and "max_sieve_error_pp" in csv.read_text().splitlines()[0]


def test_validate_missing_file(tmp_path, capsys):
    rc = main(["forms", "validate", str(tmp_path / "none.nc")])
    assert rc == 2 and "none.nc" in capsys.readouterr().err
