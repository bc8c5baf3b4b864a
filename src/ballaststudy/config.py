"""Configuration: YAML files validated by the JSON schemas in ballaststudy/schemas (the same
ones the Snakefile validates with), plus domain checks. Every error names file, key and the
allowed range in one line."""

import copy
import zlib

from .forms.objective import FormParams, ObjectiveError, build_objective
from .schema import ConfigError, fill_defaults, load_schema, load_yaml, schema_path, validate  # noqa: F401 (re-exported)



def load_config(path):
    """The study config, validated, with defaults filled."""
    cfg = validate(load_yaml(path), "config", path)
    if cfg.get("forms") is None:
        cfg["forms"] = {}
    fill_defaults(cfg["forms"], load_schema("config")["properties"]["forms"])
    return check_domain(cfg, path)


# (section, lower key, upper key, strictly below): pairs of bounds the schema cannot relate
ORDERED_PAIRS = (
    ("rig.box.loading", "cyclic_min_kN", "cyclic_max_kN", True),
    ("rig.box.loading", "cyclic_v_min_m_s", "cyclic_v_max_m_s", False),
    ("rig.box.assembly", "plate_width_m", "width_m", False),
    ("rig.biaxial.loading", "deviator_min_kPa", "deviator_max_kPa", True),
    ("rig.biaxial.loading", "platen_v_min_m_s", "platen_v_max_m_s", False),
    ("bpm", "radius_min_mm", "radius_max_mm", False),
    ("calibration.parameters.F_str_co", "min", "max", True),
    ("calibration.parameters.mu", "min", "max", True),
    ("calibration.parameters.E_star", "min", "max", True),
    ("calibration.parameters.kappa_star", "min", "max", True),
)


def _section(cfg, dotted):
    for part in dotted.split("."):
        cfg = (cfg or {}).get(part) or {}
    return cfg


def _default(section, key):
    """The value a stage uses for a key the config leaves out (its params class' default)."""
    from dataclasses import fields
    if section == "bpm":
        from .bpm.params import BpmParams
        d = {f.name: f.default for f in fields(BpmParams)}
        return d[key.removesuffix("_mm")] * 1e3 if key.endswith("_mm") else d.get(key)
    if section.startswith("calibration"):
        return None                 # required by the schema where they apply
    if section.startswith("rig.biaxial"):
        from .rig.biaxial import BiaxialParams as cls
    else:
        from .rig.params import RigParams as cls
    return {f.name: f.default for f in fields(cls)}.get(key)


def check_domain(cfg, file):
    """Checks across keys that a schema cannot state (on the values the stages will use,
    defaults included); ConfigError naming key and range."""
    for section, lo_key, hi_key, strict in ORDERED_PAIRS:
        sec = _section(cfg, section)
        lo, hi = (sec.get(k, _default(section, k)) for k in (lo_key, hi_key))
        if lo is not None and hi is not None and not (lo < hi if strict else lo <= hi):
            relation = "below" if strict else "at most"
            raise ConfigError(file, f"{section}.{lo_key}",
                              f"{lo:g} must be {relation} {section}.{hi_key} ({hi:g})")
    loads = _section(cfg, "rig.box.loading").get("static_loads_kN") or []
    if any(b <= a for a, b in zip(loads, loads[1:])):
        raise ConfigError(file, "rig.box.loading.static_loads_kN", f"{loads} must increase step by step")
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
