"""Stage 'forms': one database from its definition to netCDF + STL archive + provenance."""

import json
from pathlib import Path

from ..atomic import atomic_path
from ..provenance import Recorder
from .database import to_dataset, write_netcdf, write_stl_archive
from .generator import generate
from .objective import build_objective


def output_paths(out_dir, name):
    out_dir = Path(out_dir)
    return out_dir / f"{name}.nc", out_dir / f"{name}.stl.zip"


def generate_database(name, definition, seed, params, out_dir, config_files=(), progress=None):
    """Generate database `name` and write `<out_dir>/<name>.nc` and `.stl.zip` (atomically,
    only after the whole database succeeded), each with its `.prov.json` record. Returns the
    netCDF path."""
    recorder = Recorder("forms generate", inputs=config_files,
                        params={"database": name, "definition": definition, "forms": params.__dict__},
                        seed=seed)
    objective = build_objective(name, definition, params)
    stones = generate(objective, seed, params, progress)
    recorder.finish()
    ds = to_dataset(objective, stones, seed, params, recorder.json())
    nc, stl = output_paths(out_dir, name)
    # both files appear together or not at all
    with atomic_path(stl) as stl_tmp, atomic_path(nc) as nc_tmp:
        write_stl_archive(ds, stl_tmp)
        write_netcdf(ds, nc_tmp)
    # one record per output, so `provenance verify` also notices a deleted or edited archive
    recorder.write_beside(nc)
    recorder.write_beside(stl)
    return nc


def definition_json(definition):
    """Canonical JSON of a definition (Snakemake params: a change reruns only this database)."""
    return json.dumps(definition, sort_keys=True)
