"""Every subcommand that reads a file or writes into a folder refuses a bad one in one line:
`ballaststudy: error: <file>: ...` on stderr, exit code 2, no traceback, nothing written.

A table of (subcommand, argument) x corrupt variants, each run in-process through
`ballaststudy.cli.main` with every other argument valid, so the error must be the bad one's."""

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh
import xarray as xr
import yaml

from ballaststudy.cli import main
from ballaststudy.rig.library import synthetic_library
from ballaststudy.study.aggregate import BEHAVIOURS

ROOT = Path(__file__).resolve().parents[2]
AS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0   # root writes through chmod 0o500

# {argument:slot type}; outputs go to fresh paths in the case's folder
ROWS = {
    "forms generate": "forms generate G_1-1 --config {config:yaml} --out {out:dir_out}",
    "forms validate": "forms validate {forms:nc} --csv {out:file_out}",
    "forms report": "forms report {forms:nc} --out {out:dir_out}",
    "provenance show": "provenance show {forms:any} --results {results:results}",
    "provenance verify": "provenance verify --results {results:results_rw}",
    "bpm build": "bpm build {forms:nc} --out {out:file_out} --config {config:yaml}",
    "case assemble": "case assemble {bpm:nc} --case 0 --out {out:file_out} --config {config:yaml}",
    "case run": "case run {assembled:nc} --cycles 1 --out {out:file_out} --config {config:yaml} "
                "--conditions {conditions:yaml} --no-vtk --no-figures",
    "study aggregate": "study aggregate {metrics:nc} --forms {forms:nc} --out {out:file_out}",
    "study iri": "study iri {study:nc} --out {out:dir_out} --resamples 100",
    "study optimise": "study optimise {study:nc} --out {out:dir_out} --resamples 100",
    "measured import": "measured import {conditions:yaml} --out {out:file_out} --data-dir {data:dir}",
    "measured compare": "measured compare {measured:nc} {metrics:nc} --out {out:file_out}",
    "config check": "config check --config {config:yaml}",
    "parametric report": "parametric report {metrics:nc} --out-dir {out:dir_out}",
    "forms evaluate": "forms evaluate {stl:stl} --density 2650",
}
# the checkpoint `case run` resumes from: not an argument, it sits beside --out
CHECKPOINT_OF = {"case run": lambda paths: paths["out"].with_name(paths["out"].stem + ".checkpoint.npz")}

# a valid file of another kind, for each kind (the confusable one where there is one)
WRONG_KIND = {"forms": "bpm", "bpm": "forms", "assembled": "bpm", "metrics": "forms",
              "study": "metrics", "measured": "metrics", "config": "conditions", "conditions": "config"}
GARBAGE = np.random.default_rng(0).bytes(777)
PNG = b"\x89PNG\r\n\x1a\n" + bytes(64)


def _write(data):
    def make(path, name, valid):
        path.write_bytes(data)
        return path
    return make


def _copy_of(which):
    def make(path, name, valid):
        shutil.copy(valid[which(name)], path)
        return path
    return make


def _truncated(path, name, valid):
    data = valid[name].read_bytes()
    path.write_bytes(data[:len(data) // 2])
    return path


def _missing(path, name, valid):
    return path


def _folder(path, name, valid):
    path.mkdir()
    return path


def _record(text):
    def make(path, name, valid):
        path.mkdir()
        (path / "x.nc.prov.json").write_bytes(text)
        return path
    return make


def _store_blocked(path, name, valid):
    path.mkdir()
    (path / "provenance").write_text("a file where the store's folder goes")
    return path


def _key_twice(path, name, valid):
    """The valid file with its first top-level `key: value` line again: the same value, so
    only the repeat itself is wrong."""
    text = valid[name].read_text()
    path.write_text(text + re.search(r"^\w+: \S.*$", text, re.M)[0] + "\n")
    return path


def _under_file(path, name, valid):
    path.parent.joinpath("blocker").write_text("a regular file")
    return path.parent / "blocker" / path.name


def _read_only(path, name, valid):
    ro = path.parent / "read_only"
    ro.mkdir()
    ro.chmod(0o500)
    return ro / path.name


_OUT = {"under a regular file": _under_file, **({} if AS_ROOT else {"read-only folder": _read_only})}
_IN = {"missing": _missing, "directory": _folder, "empty": _write(b""), "garbage bytes": _write(GARBAGE)}
VARIANTS = {
    "nc": {**_IN, "wrong kind": _copy_of(WRONG_KIND.get), "YAML text": _write(b"seed: 1\nrig: {kind: box}\n"),
           "PNG": _write(PNG), "truncated": _truncated},
    "yaml": {**_IN, "netCDF": _copy_of(lambda name: "forms"), "wrong kind": _copy_of(WRONG_KIND.get),
             "key given twice": _key_twice},
    "npz": {"directory": _folder, "empty": _write(b""), "garbage bytes": _write(GARBAGE),
            "netCDF": _copy_of(lambda name: "forms"), "wrong kind": _copy_of(lambda name: "other_npz"),
            "truncated": _truncated, "unusable contents": _copy_of(lambda name: "checkpoint")},
    "stl": {**_IN, "netCDF": _copy_of(lambda name: "forms"), "PNG": _write(PNG), "truncated": _truncated},
    "any": {"missing": _missing, "directory": _folder},
    "dir": {"missing": _missing, "a file": _write(GARBAGE)},
    "results": {"missing": _missing, "a file": _write(GARBAGE), "damaged record": _record(GARBAGE),
                "JSON not a record": _record(b'{"a": 1}')},
    "file_out": {**_OUT, "a folder": _folder},
    "dir_out": {**_OUT, "a file": _write(b"x")},
}
VARIANTS["results_rw"] = {**VARIANTS["results"], "store under a regular file": _store_blocked}
_SLOT = re.compile(r"\{(\w+):(\w+)\}")


def _cases():
    for command, template in ROWS.items():
        slots = [(name, kind) for name, kind in _SLOT.findall(template)]
        if command in CHECKPOINT_OF:
            slots.append(("checkpoint", "npz"))
        for name, kind in slots:
            for variant in VARIANTS[kind]:
                yield command, name, kind, variant


CASES = list(_cases())


@pytest.fixture(scope="module")
def valid(tmp_path_factory):
    """One small valid file (or folder) per kind; only what the commands read before the slot
    under test (the kinds are recognised by the variables/attributes their writers store)."""
    d = tmp_path_factory.mktemp("valid")
    ds = {
        "forms": xr.Dataset({k: ("stone", [0.05, 0.04]) for k in ("a", "b", "c", "mass")},
                            attrs={"database": "db"}),
        "bpm": synthetic_library(2, r0=0.006, seed=1),
        "assembled": xr.Dataset({"engine_checkpoint": ("nbytes", np.zeros(8, np.uint8))},
                                attrs={"rig_kind": "biaxial", "rig_layout_json": "{}", "rig_params_json": "{}"}),
        "metrics": xr.Dataset({**{k: ("cycle", np.zeros(2)) for k in BEHAVIOURS},
                               "axial_strain": ("cycle", [0.001, 0.002])}, attrs={"database": "db", "case": 0}),
        "study": xr.Dataset({k: (("database", "case", "cycle"), np.zeros((1, 1, 2))) for k in BEHAVIOURS}),
        "measured": xr.Dataset({"axial_strain": ("cycle", [0.01, 0.02])}, coords={"cycle": [1.0, 10.0]},
                               attrs={"conditions_file": "test.yaml", "rig": "triaxial"}),
    }
    files = {}
    for name, data in ds.items():
        files[name] = d / f"{name}.nc"
        data.to_netcdf(files[name])
    files["checkpoint"] = d / "run.checkpoint.npz"
    np.savez(files["checkpoint"], **{k: np.zeros(64) for k in ("engine", "state", "layout", "params", "cycles")})
    files["other_npz"] = d / "other.npz"
    np.savez(files["other_npz"], x=np.zeros(3))
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / "config" / "databases.yaml")
    files["config"] = d / "config.yaml"
    files["config"].write_text(yaml.safe_dump(cfg))
    (d / "ax.dat").write_text("1, 0.01\n10, 0.02\n")
    files["conditions"] = d / "test.yaml"
    files["conditions"].write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=30, deviator_max_kPa=230,
        curves=[dict(file="ax.dat", quantity="axial_strain", units="1", sign="compression_positive")])))
    files["stl"] = d / "stone.stl"
    trimesh.creation.box((60.0, 40.0, 30.0)).export(files["stl"])
    for folder in ("results", "data"):
        files[folder] = d / folder
        files[folder].mkdir()
    return files


def _tree(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.mark.parametrize("command, slot, kind, variant", CASES,
                         ids=[f"{c}-{s}-{v}".replace(" ", "_") for c, s, _, v in CASES])
def test_bad_file_is_one_line_exit_2(command, slot, kind, variant, valid, tmp_path, capsys):
    case = tmp_path / "case"
    case.mkdir()
    paths = {name: (case / ("report" if k == "dir_out" else "result.nc") if k.endswith("_out") else valid[name])
             for name, k in _SLOT.findall(ROWS[command])}
    target = CHECKPOINT_OF[command](paths) if slot == "checkpoint" else case / f"bad_{slot}{paths[slot].suffix}"
    bad = VARIANTS[kind][variant](target, slot, valid)
    if slot != "checkpoint":
        paths[slot] = bad
    argv = _SLOT.sub(lambda m: str(paths[m[1]]), ROWS[command]).split()
    before, before_valid = _tree(case), _tree(valid["results"].parent)
    try:
        code = main(argv)
    finally:
        if bad.parent.name == "read_only":
            bad.parent.chmod(0o700)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1 and err.startswith("ballaststudy: error: "), err
    assert str(bad) in err, err
    assert _tree(case) == before and _tree(valid["results"].parent) == before_valid   # nothing written


def test_the_table_covers_every_command_and_variant(fuzz_report):
    pairs = {(c, v) for c, _, _, v in CASES}
    fuzz_report.append(f"corrupt files: {len(CASES)} cases, {len(pairs)} (subcommand, variant) pairs over "
                       f"{len(ROWS)} subcommands{'' if AS_ROOT else ' (with read-only folders)'}: "
                       + "; ".join(f"{c}: {', '.join(sorted(v for c2, v in pairs if c2 == c))}" for c in ROWS))
    assert {c for c, _ in pairs} == set(ROWS)
    assert {v for _, v in pairs} == {v for k in VARIANTS.values() for v in k}


# ------------------------------------------------------------------ command-line numbers


def _typed_options():
    """(command, option, type) of every option of every subcommand that takes a number."""
    import argparse

    from ballaststudy.cli import build_parser

    def walk(parser, prefix):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    yield from walk(sub, f"{prefix} {name}")
            elif action.type is not None and action.option_strings:
                yield prefix.strip(), action.option_strings[-1], action.type
    return list(walk(build_parser(), ""))


def test_every_numeric_option_has_a_range():
    """No bare int/float option: each goes through argtypes, which states the allowed range."""
    options = _typed_options()
    assert len(options) >= 12
    bare = [(c, o) for c, o, t in options if t in (int, float)]
    assert not bare, bare


@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e400", str(10**30), "ten", ""])
def test_numeric_options_refuse_non_finite_huge_and_text(value):
    import argparse
    for command, option, parse in _typed_options():
        if parse.__qualname__.split(".")[0] not in ("integer", "number"):
            continue
        with pytest.raises(argparse.ArgumentTypeError, match="allowed: an? (integer|number) >= "):
            parse(value)


def test_a_bad_option_is_one_line(capsys):
    from ballaststudy.cli import main
    with pytest.raises(SystemExit) as stop:
        main(["case", "run", "x.nc", "--cycles", "0", "--out", "m.nc"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert err.startswith("ballaststudy: error: ballaststudy case run: argument --cycles: '0' is not allowed; "
                          "allowed: an integer >= 1")
