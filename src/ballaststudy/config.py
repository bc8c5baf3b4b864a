"""Configuration: YAML files validated by the JSON schemas in ballaststudy/schemas (the same
ones the Snakefile validates with), plus domain checks. Every error names file, key and the
allowed range in one line."""

import copy
import zlib
from importlib import resources
from pathlib import Path

import jsonschema
import yaml

from .forms.objective import FormParams, ObjectiveError, build_objective


class ConfigError(ValueError):
    """Bad input: `file: key: message`."""

    def __init__(self, file, key, message):
        super().__init__(f"{file}: {key}: {message}" if key else f"{file}: {message}")
        self.file, self.key = str(file), key


def schema_path(name):
    """Path of a packaged schema, e.g. schema_path('config')."""
    return Path(resources.files("ballaststudy") / "schemas" / f"{name}.schema.yaml")


def _key(path):
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _describe(error):
    """jsonschema's message with the allowed range spelled out."""
    s = error.schema if isinstance(error.schema, dict) else {}
    lo = s.get("minimum", s.get("exclusiveMinimum"))
    hi = s.get("maximum", s.get("exclusiveMaximum"))
    if error.validator in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        lo_s = "" if lo is None else (f"> {lo}" if "exclusiveMinimum" in s else f">= {lo}")
        hi_s = "" if hi is None else (f"< {hi}" if "exclusiveMaximum" in s else f"<= {hi}")
        return f"{error.instance!r} is out of range; allowed: {' and '.join(x for x in (lo_s, hi_s) if x)}"
    if error.validator == "oneOf":
        # a value of the right kind but out of range: report that, not the choice of kinds
        inner = [c for c in error.context if c.validator != "type"]
        if inner:
            return _describe(max(inner, key=lambda c: len(c.absolute_path)))
        return f"{error.instance!r} is not allowed here; {error.schema.get('description', 'see the schema')}"
    return error.message


def validate(data, schema_name, file):
    """Validate against a packaged schema, filling its defaults; raise ConfigError on the first error."""
    schema = yaml.safe_load(schema_path(schema_name).read_text())
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(data), key=lambda e: (len(e.absolute_path), list(map(str, e.absolute_path))))
    if errors:
        e = errors[0]
        inner = [c for c in (e.context or []) if c.validator != "type"]
        where = max(inner, key=lambda c: len(c.absolute_path)) if e.validator == "oneOf" and inner else e
        raise ConfigError(file, _key(where.absolute_path), _describe(e))
    _fill_defaults(data, schema)
    return data


def _fill_defaults(data, schema):
    for key, sub in schema.get("properties", {}).items():
        if isinstance(sub, dict) and "default" in sub and key not in data:
            data[key] = copy.deepcopy(sub["default"])
        if isinstance(sub, dict) and isinstance(data.get(key), dict) and sub.get("type") == "object":
            _fill_defaults(data[key], sub)


def load_yaml(path):
    path = Path(path)
    if not path.is_file():
        raise ConfigError(path, None, "file not found")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        raise ConfigError(path, None, f"not valid YAML: {err}") from None
    return {} if data is None else data


def load_config(path):
    """The study config, validated, with defaults filled."""
    cfg = validate(load_yaml(path), "config", path)
    if cfg.get("forms") is None:
        cfg["forms"] = {}
    _fill_defaults(cfg["forms"], yaml.safe_load(schema_path("config").read_text())["properties"]["forms"])
    return check_domain(cfg, path)


def check_domain(cfg, file):
    """Checks across keys that a schema cannot state; ConfigError naming key and range."""
    loading = ((cfg.get("rig") or {}).get("box") or {}).get("loading") or {}
    key = "rig.box.loading."
    lo, hi = loading.get("cyclic_min_kN"), loading.get("cyclic_max_kN")
    if lo is not None and hi is not None and not lo < hi:
        raise ConfigError(file, key + "cyclic_min_kN",
                          f"{lo:g} kN must be below {key}cyclic_max_kN ({hi:g} kN)")
    loads = loading.get("static_loads_kN") or []
    if any(b <= a for a, b in zip(loads, loads[1:])):
        raise ConfigError(file, key + "static_loads_kN", f"{loads} must increase step by step")
    bpm = cfg.get("bpm") or {}
    rmin, rmax = bpm.get("radius_min_mm"), bpm.get("radius_max_mm")
    if rmin is not None and rmax is not None and not rmin <= rmax:
        raise ConfigError(file, "bpm.radius_min_mm", f"{rmin:g} mm must not exceed bpm.radius_max_mm ({rmax:g} mm)")
    return cfg


def form_params(cfg):
    f = cfg["forms"]
    return FormParams(n_vertices=f["n_vertices"], ab_ratio_max=f["ab_ratio_max"],
                      cb_ratio_min=f["cb_ratio_min"], batch=f["batch"])


def load_databases(path, params=FormParams()):
    """Database definitions {name: definition} with `defaults` merged, each checked by building
    its objective (ranges, monotone grading, categories, SI <= FI, reachable targets)."""
    raw = validate(load_yaml(path), "databases", path)
    defaults = raw.get("defaults", {})
    out = {}
    for name, entry in raw["databases"].items():
        d = {**copy.deepcopy(defaults), **entry}
        for key in ("mass_kg", "grading", "shape_index", "particle_length_index", "materials"):
            if key not in d:
                raise ConfigError(path, f"databases.{name}.{key}", "missing (and not in defaults)")
        d.setdefault("flakiness_index", None)
        try:
            build_objective(name, d, params)
        except ObjectiveError as err:
            raise ConfigError(path, f"databases.{name}.{err.key}", str(err)) from None
        out[name] = d
    return out


def select_databases(cfg, databases, file="config"):
    """Names the study runs, in databases-file order; unknown names are an error."""
    wanted = cfg["databases"]
    if wanted == "all":
        return list(databases)
    unknown = [n for n in wanted if n not in databases]
    if unknown:
        raise ConfigError(file, "databases", f"unknown database {unknown[0]!r}; allowed: "
                          + ", ".join(databases) + ", or 'all'")
    return list(wanted)


def job_seed(study_seed, key):
    """The one seed formula: a job's seed from the study seed and the job's key (e.g.
    "G_1-1", "G_1-1/bpm", "G_1-1/case3") via CRC-32 (Python's hash() is salted per process
    and so not reproducible)."""
    return (int(study_seed) * 1_000_003 + zlib.crc32(key.encode())) % 2**63


def database_seed(study_seed, name, definition):
    """One deterministic seed per database: explicit, or job_seed(study seed, name)."""
    if definition.get("seed") is not None:
        return int(definition["seed"])
    return job_seed(study_seed, name)
