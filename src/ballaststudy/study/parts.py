"""A study run in parts (issue 35: the thesis-scale run is longer than a session of the
machine that runs it, and its results folder does not outlive the session).

`pack_part` keeps what a part's results folder holds for the study in a small folder that
can be kept (committed, copied): the part's study.nc (the aggregate of its cases) and the
provenance records of its jobs in one JSON list, with the time logs of its commands.
`merge_parts` joins such folders into one results folder, as a whole run would have made
it: study.nc with every (database, case) of the parts (each from the one part that ran it)
and every record; the IRI, optimisation and record stages then read it as they read a run's.
"""

import json
from pathlib import Path

import numpy as np
import xarray as xr

from ..atomic import atomic_copy, atomic_path
from ..inputs import input_dir, input_file, open_netcdf
from ..provenance import Recorder
from ..provenance.store import load_records
from ..schema import ConfigError
from .aggregate import BEHAVIOURS, case_label_key, database_order_key, netcdf_encoding
from .report import extent_line
from .timing import of_databases, read_time_log

PART_STUDY = "study.nc"
PART_RECORDS = "records.json"       # the part's provenance records: a JSON list
PART_README = "README.md"
# per (database, case): the value where no case is (or a part from before the variable)
_FILLS = {"cycles_run": np.int32(0), "assembly_stages_at_limit": np.int32(-1),
          "assembly_force_ratio": np.float64(np.nan), "seating": np.float64(np.nan)}


def pack_part(results_dir, out_dir, time_logs=(), command=None):
    """Keep the study of ``results_dir`` (its study.nc and the records of its databases'
    jobs and of the study steps) and the given time logs in ``out_dir``; return the paths."""
    results = input_dir(results_dir, "expected a part's results folder")
    study_path = input_file(results / "study.nc", "expected study.nc (run the part's study stages first)")
    study = open_netcdf(study_path, "study", require=tuple(BEHAVIOURS))
    records = of_databases(load_records(results), [str(d) for d in study.database.values])
    # read each log as the record stage will, so a part never keeps one record refuses
    logs = [Path(read_time_log(p)["log"]) for p in time_logs]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    kept = kept_study(study)
    with atomic_path(out / PART_STUDY) as tmp:
        kept.to_netcdf(tmp, engine="netcdf4", encoding=netcdf_encoding(kept))
    written = [out / PART_STUDY]
    written.append(_write_records(out / PART_RECORDS, records))
    written += [atomic_copy(p, out / Path(p).name) for p in logs]
    with atomic_path(out / PART_README) as tmp:
        tmp.write_text(_part_readme(study, records, [p.name for p in map(Path, logs)], command))
    return written + [out / PART_README]


def kept_study(study):
    """The part's study as kept: the behaviours the study stages read and the per-case
    counts; the rig's other per-cycle records (a third of the size: force bounds, plate
    position, steps) stay in each case's metrics.nc."""
    names = [n for n in (*BEHAVIOURS, *_FILLS) if n in study]
    dropped = sorted(n for n in study.data_vars if n not in names)
    kept = study[names].copy()
    kept.attrs = dict(study.attrs, kept_by_study_pack=(
        "the behaviours and per-case counts of the part's study.nc; left out (in each case's metrics.nc): "
        + (", ".join(dropped) or "nothing")))
    return kept


def _part_readme(study, records, logs, command):
    """What the part holds, in words."""
    ran = (study.cycles_run.values > 0).sum(axis=1)
    cases = ", ".join(f"{d} {n}" for d, n in zip(map(str, study.database.values), ran))
    jobs = len({json.dumps(r, sort_keys=True) for r in records.values()})
    return "\n".join([
        "# A part of a study run", "",
        f"Written by `{command or 'ballaststudy study pack'}`; do not edit. Join parts with "
        "`ballaststudy study merge PART ... --out RESULTS`, then run the study's iri, optimise and record "
        "stages on RESULTS.", "",
        f"- Extent: {extent_line(study)}", f"- Cases run per database: {cases}",
        f"- {PART_STUDY}: the part's study (aggregate of its cases); {PART_RECORDS}: the provenance "
        f"records of its {jobs} job{'s' if jobs != 1 else ''}; time logs: {', '.join(logs) or 'none'}", ""])


def _write_records(path, records):
    """{output: record} as a JSON list, each job once (a job's record sits beside each output)."""
    unique = {json.dumps(rec, sort_keys=True): rec for rec in records.values()}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps([unique[k] for k in sorted(unique)], indent=1, sort_keys=True))
    return path


def load_part_records(path):
    """{output path: record} from a part's records.json (a JSON list of records)."""
    try:
        items = json.loads(input_file(path, "expected a part's records.json").read_text())
    except json.JSONDecodeError as err:
        raise ConfigError(path, None, f"not valid JSON ({err.msg}); expected a list of provenance records") from None
    if not isinstance(items, list) or not all(isinstance(r, dict) and "output" in r for r in items):
        raise ConfigError(path, None, "not a list of provenance records (each a mapping with 'output')")
    return {str(Path(p)): rec for rec in items for p in rec["output"]}


# steps whose settings must be one across a study's parts, and what may differ between their
# jobs: the case index, and the scenario's cache key (a hash that includes the specimen)
SHARED_SETTINGS = {"bpm build": (), "case assemble": ("case",), "case run": ("scenario_key",)}


def _differing_key(a, b, prefix=""):
    """The first key (dotted) at which two parameter mappings differ."""
    for key in sorted(set(a) | set(b)):
        va, vb = a.get(key), b.get(key)
        if va != vb:
            return _differing_key(va, vb, f"{prefix}{key}.") if isinstance(va, dict) and isinstance(vb, dict) \
                else f"{prefix}{key}"
    return prefix.rstrip(".")


def check_one_setting(per_part):
    """Refuse parts whose BPM, assembly or loading jobs ran with other settings (another
    config or material): merged, they would not be one study. per_part: [(records file,
    {output: record})]."""
    seen = {}
    for path, records in per_part:
        for rec in records.values():
            if rec.get("step") not in SHARED_SETTINGS:
                continue
            params = {k: v for k, v in rec.get("params", {}).items() if k not in SHARED_SETTINGS[rec["step"]]}
            first = seen.setdefault(rec["step"], (path, params))
            if params != first[1]:
                raise ConfigError(path, f"{rec['step']}.params.{_differing_key(first[1], params)}",
                                  f"differs from the same step's in {first[0]}: the parts are not one study")


def _database_coords(ds):
    """Coordinates along `database` (other than its labels): name -> (dims, attrs)."""
    return {n: (c.dims, dict(c.attrs)) for n, c in ds.coords.items()
            if c.dims and c.dims[0] == "database" and n != "database"}


def _same(a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind in "fc" or b.dtype.kind in "fc":
        return a.shape == b.shape and bool(np.allclose(a, b, rtol=1e-12, atol=0.0, equal_nan=True))
    return a.shape == b.shape and bool(np.all(a == b))


def _common_variables(parts):
    """The (database, case, cycle) variables every part holds, with the first part's attrs."""
    per_case = [{n for n, v in ds.data_vars.items() if v.dims == ("database", "case", "cycle")} for _, ds in parts]
    common = set.intersection(*per_case)
    first = parts[0][1]
    return {n: dict(first[n].attrs) for n in first.data_vars if n in common}


def merge_studies(parts):
    """One study Dataset from [(path, study Dataset)]: the union of databases, cases and
    cycles; each (database, case) from the part that ran it (cycles_run > 0), a second part
    running it too is an error, as are parts whose form databases disagree."""
    if not parts:
        raise ConfigError("study merge", None, "no parts given")
    dbs = sorted({str(d) for _, ds in parts for d in ds.database.values}, key=database_order_key)
    labels = [c for _, ds in parts for c in ds.case.values.tolist()]
    cases = sorted(set(labels), key=case_label_key)
    cycles = np.unique(np.concatenate([ds.cycle.values for _, ds in parts]))
    variables = _common_variables(parts)
    shape = (len(dbs), len(cases), len(cycles))
    data = {n: np.full(shape, np.nan) for n in variables}
    per_case = {n: np.full(shape[:2], fill) for n, fill in _FILLS.items()}
    owner, coord_of = {}, {}
    for path, ds in parts:
        k = np.searchsorted(cycles, ds.cycle.values)
        for i, db in enumerate(map(str, ds.database.values)):
            coords = {n: ds[n].values[i] for n in _database_coords(ds)}
            if db in coord_of and not all(_same(coords[n], coord_of[db][1][n]) for n in coords):
                raise ConfigError(path, "database", f"{db}: its form database differs from the one in "
                                                    f"{coord_of[db][0]} (not one study)")
            coord_of.setdefault(db, (path, coords))
            for j, case in enumerate(ds.case.values.tolist()):
                if int(ds.cycles_run.values[i, j]) == 0:
                    continue
                I, J = dbs.index(db), cases.index(case)
                if (I, J) in owner:
                    raise ConfigError(path, "case", f"{db} case {case} is also in {owner[I, J]}; keep one part's")
                owner[I, J] = path
                for n in variables:
                    data[n][I, J, k] = ds[n].values[i, j]
                for n in _FILLS:
                    if n in ds:
                        per_case[n][I, J] = ds[n].values[i, j]
    first = parts[0][1]
    dims = ("database", "case", "cycle")
    out = {n: (dims, data[n], variables[n]) for n in variables}
    attrs_of = {n: dict(ds[n].attrs) for _, ds in reversed(parts) for n in _FILLS if n in ds}
    out.update({n: (("database", "case"), per_case[n], attrs_of[n]) for n in _FILLS if n in attrs_of})
    coords = {"database": ("database", np.array(dbs, dtype=object), dict(first.database.attrs)),
              "case": ("case", np.array(cases, dtype=first.case.dtype), dict(first.case.attrs)),
              "cycle": ("cycle", cycles, dict(first.cycle.attrs))}
    coords.update({n: (c.dims, c.values, dict(c.attrs)) for n, c in first.coords.items()
                   if "database" not in c.dims and n not in coords})
    for n, (cdims, attrs) in _database_coords(first).items():
        coords[n] = (cdims, np.stack([coord_of[db][1][n] for db in dbs]), attrs)
    attrs = {k: v for k, v in first.attrs.items() if k != "provenance"}
    return xr.Dataset(out, coords=coords, attrs=attrs)


def merge_parts(part_dirs, out_dir):
    """Write ``out_dir``/study.nc (merged) and ``out_dir``/records.json (every part's
    records); return the paths."""
    dirs = [input_dir(d, "expected a part folder (study pack)") for d in part_dirs]
    studies = [input_file(d / PART_STUDY, "expected a part's study.nc (study pack)") for d in dirs]
    record_files = [input_file(d / PART_RECORDS, "expected a part's records.json (study pack)") for d in dirs]
    parts = [(p, open_netcdf(p, "study", require=tuple(BEHAVIOURS))) for p in studies]
    per_part = [(path, load_part_records(path)) for path in record_files]
    check_one_setting(per_part)
    records = {k: rec for _, part in per_part for k, rec in part.items()}
    recorder = Recorder("study merge", inputs=[str(p) for p in studies + record_files],
                        params={"parts": [str(d) for d in dirs]})
    ds = merge_studies(parts)
    recorder.finish()
    ds.attrs["provenance"] = recorder.json()
    ds.attrs["merged_from"] = ", ".join(str(d) for d in dirs)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_path(out / PART_STUDY) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4", encoding=netcdf_encoding(ds))
    recorder.write_beside(out / PART_STUDY)
    return [out / PART_STUDY, _write_records(out / PART_RECORDS, records)]
