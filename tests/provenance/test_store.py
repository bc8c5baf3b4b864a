"""Provenance: records beside outputs, lineage back to the config, verify flags edits."""

import hashlib
import json

import pytest
import yaml

from ballaststudy.cli import main
from ballaststudy.provenance import Recorder
from ballaststudy.provenance.store import lineage, load_records, verify


def _make(tmp_path, name, inputs, text):
    out = tmp_path / "results" / name
    out.parent.mkdir(parents=True, exist_ok=True)
    rec = Recorder(f"make {name}", inputs=inputs, params={"k": 1}, seed=7)
    out.write_text(text)
    rec.finish()
    rec.write_beside(out)
    return out


def test_lineage_reaches_the_config_and_verify_flags_an_edited_input(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = tmp_path / "config.yaml"
    cfg.write_text("seed: 1\n")
    a = _make(tmp_path, "a.nc", [cfg], "A")
    b = _make(tmp_path, "b.nc", [a], "B")
    records = load_records(tmp_path / "results")
    lines = lineage(b, records)
    assert lines[0].startswith(str(b)) and "make b.nc" in lines[0], lines
    assert any(str(a) in ln and "make a.nc" in ln for ln in lines), lines
    assert lines[-1].strip() == f"{cfg}  (source)", lines
    assert verify(records) == []

    cfg.write_text("seed: 2\n")
    problems = verify(load_records(tmp_path / "results"))
    assert [p for p, _ in problems] == [str(cfg)], problems
    assert "stale" in problems[0][1]
    with pytest.raises(SystemExit) as stop:
        main(["provenance", "verify", "--results", str(tmp_path / "results")])
    assert stop.value.code == 1
    assert "stale" in capsys.readouterr().out


def test_record_holds_hashes_params_seed_versions(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("x: 1\n")
    out = _make(tmp_path, "o.nc", [cfg], "O")
    rec = json.loads((out.parent / "o.nc.prov.json").read_text())
    assert rec["inputs"][str(cfg)] == hashlib.sha256(b"x: 1\n").hexdigest()
    assert rec["seed"] == 7 and rec["params"] == {"k": 1} and len(rec["params_sha256"]) == 64
    assert rec["package"]["name"] == "ballaststudy" and rec["libraries"]["numpy"]
    assert rec["started"] <= rec["finished"]
    assert rec["output"][str(out)] == hashlib.sha256(b"O").hexdigest()


def _verify(results, capsys):
    """(exit code, stdout) of `ballaststudy provenance verify`."""
    try:
        rc = main(["provenance", "verify", "--results", str(results)])
    except SystemExit as stop:
        rc = stop.code
    return rc, capsys.readouterr().out


def test_verify_covers_the_stl_archive_of_forms_generate(tmp_path, capsys):
    db_file = tmp_path / "dbs.yaml"
    db_file.write_text(yaml.safe_dump({"databases": {"tiny": {
        "mass_kg": 3, "grading": "G_CRB B", "shape_index": 30, "particle_length_index": 0,
        "materials": {"hard": {"mass_fraction": 1.0, "density_kg_m3": 2700}}}}}))
    cfg = tmp_path / "config.yaml"
    cfg.write_text(yaml.safe_dump({"seed": 7, "databases_file": str(db_file), "databases": "all", "forms": {}}))
    results = tmp_path / "results"
    assert main(["forms", "generate", "--all", "--out", str(results / "forms"), "--config", str(cfg),
                 "--quiet"]) == 0
    archive = results / "forms" / "tiny.stl.zip"
    assert _verify(results, capsys)[0] == 0

    archive.write_bytes(archive.read_bytes() + b"\0")
    rc, out = _verify(results, capsys)
    assert rc == 1 and f"{archive}: output changed after it was written" in out, out

    archive.unlink()
    rc, out = _verify(results, capsys)
    assert rc == 1 and f"{archive}: output missing" in out, out
    assert "tiny.nc:" not in out, f"only the archive is at fault: {out}"


def test_figures_written_by_a_step_are_in_its_record(tmp_path):
    """write_beside(..., also=figures): `show` finds the figure's step, `verify` misses it when deleted."""
    main, fig = tmp_path / "metrics.nc", tmp_path / "case.png"
    main.write_bytes(b"data")
    fig.write_bytes(b"png")
    rec = Recorder("case run")
    rec.finish()
    rec.write_beside(main, also=[fig])
    records = load_records(tmp_path)
    assert records[str(fig)]["step"] == "case run" and not verify(records)
    fig.unlink()
    assert verify(load_records(tmp_path)) == [(str(fig), "output missing (recorded by 'case run')")]
