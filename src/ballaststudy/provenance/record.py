"""A provenance record per output: input files with sha256, params (and their hash), seed,
package version and git commit, library versions, start/end time, host and machine.

Records are JSON, stored as the netCDF global attribute `provenance` and beside the output
as `<output>.prov.json`.
"""

import datetime as _dt
import hashlib
import json
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from .. import __version__
from ..atomic import atomic_path

_LIBRARIES = ("numpy", "scipy", "numba", "trimesh", "xarray", "netCDF4", "shapely", "pandas")


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def params_hash(params):
    return hashlib.sha256(json.dumps(params, sort_keys=True, default=str).encode()).hexdigest()


def _git_commit():
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "-C", str(here), "describe", "--always", "--dirty", "--abbrev=40"],
                             capture_output=True, text=True, timeout=10)
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def _versions():
    out = {}
    for lib in _LIBRARIES:
        try:
            out[lib] = metadata.version(lib)
        except metadata.PackageNotFoundError:
            out[lib] = None
    return out


def _machine():
    """What ran the step: processor model (Linux: /proc/cpuinfo), logical CPUs, OS."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"processor": model, "cpus": os.cpu_count(), "system": f"{platform.system()} {platform.release()}"}


def _now():
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


class Recorder:
    """Collects one output's provenance: create at the start of the job, `finish` at the end."""

    def __init__(self, step, inputs=(), params=None, seed=None):
        self.record = {
            "step": step,
            "inputs": {str(p): sha256_file(p) for p in inputs},
            "params": params or {},
            "params_sha256": params_hash(params or {}),
            "seed": seed,
            "package": {"name": "ballaststudy", "version": __version__, "git": _git_commit()},
            "libraries": _versions(),
            "python": platform.python_version(),
            "host": platform.node(),
            "machine": _machine(),
            "started": _now(),
        }

    def finish(self):
        self.record["finished"] = _now()
        return self.record

    def write_beside(self, output, also=()):
        """Write `<output>.prov.json` with the sha256 of the output and of the files `also`
        made by the same step (figures, VTK), so every file the step wrote has a record (atomic)."""
        output = Path(output)
        rec = dict(self.record, output={str(p): sha256_file(p) for p in (output, *map(Path, also))})
        side = output.with_name(output.name + ".prov.json")
        with atomic_path(side) as tmp:
            tmp.write_text(json.dumps(rec, indent=1, sort_keys=True, default=str))
        return side

    def json(self):
        return json.dumps(self.record, sort_keys=True, default=str)
