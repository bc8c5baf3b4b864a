"""The provenance store: every `<output>.prov.json` under the results folder, queried as one.

`lineage(path)` follows an output back through the records that made its inputs to the
config files; `verify()` re-hashes every input and output and says what is stale or changed.
"""

import json
from pathlib import Path

from ..atomic import atomic_path
from ..schema import ConfigError
from ..inputs import input_file
from .record import sha256_file

_RECORD = "expected a provenance record (JSON written beside each output)"
_KEYS = ("step", "output", "params_sha256", "package", "finished")   # what lineage/verify read


def _read_record(side):
    """One sidecar record; ConfigError (one line) if it is not one."""
    try:
        rec = json.loads(input_file(side, _RECORD).read_bytes())
    except (UnicodeDecodeError, json.JSONDecodeError) as err:
        raise ConfigError(side, None, f"not valid JSON ({type(err).__name__}); {_RECORD}") from None
    if not isinstance(rec, dict):
        raise ConfigError(side, None, f"JSON but not a record (not a mapping); {_RECORD}")
    lacks = [k for k in _KEYS if k not in rec]
    if lacks:
        raise ConfigError(side, None, f"JSON but not a record (no key {lacks[0]!r}); {_RECORD}")
    return rec


def load_records(results_dir):
    """{output path: record} for every sidecar record under results_dir."""
    out = {}
    for side in sorted(Path(results_dir).rglob("*.prov.json")):
        rec = _read_record(side)
        for path in rec.get("output", {}):
            out[str(Path(path))] = rec
    return out


def write_store(results_dir, path):
    """All records in one JSON file (list), for people and tools that want a single file."""
    records = load_records(results_dir)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(list(records.values()), indent=1, sort_keys=True))
    return path


def lineage(path, records, depth=0, seen=None):
    """Lines describing how `path` was made, indented by generation, back to the sources."""
    seen = set() if seen is None else seen
    path = str(Path(path))
    pad = "  " * depth
    rec = records.get(path)
    if rec is None:
        return [f"{pad}{path}  (source)"]
    if path in seen:
        return [f"{pad}{path}  (see above)"]
    seen.add(path)
    lines = [f"{pad}{path}  <- {rec['step']} (seed {rec.get('seed')}, params {rec['params_sha256'][:12]}, "
             f"ballaststudy {rec['package']['version']} {rec['package'].get('git') or ''}, {rec['finished']})"]
    for inp in rec.get("inputs", {}):
        lines += lineage(inp, records, depth + 1, seen)
    return lines


def verify(records):
    """Problems found by re-hashing: (path, what) for changed/missing inputs and outputs."""
    problems = []
    for rec in {id(r): r for r in records.values()}.values():
        for kind, files in (("input", rec.get("inputs", {})), ("output", rec.get("output", {}))):
            for path, digest in files.items():
                if not Path(path).is_file():
                    problems.append((path, f"{kind} missing (recorded by '{rec['step']}')"))
                elif sha256_file(path) != digest:
                    what = "changed since it was used: outputs made from it are stale" if kind == "input" \
                        else "changed after it was written"
                    problems.append((path, f"{kind} {what} ('{rec['step']}')"))
    return sorted(set(problems))
