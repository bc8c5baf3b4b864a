"""Configuration: YAML files validated by the JSON schemas in ballaststudy/schemas (the same
ones the Snakefile validates with), plus domain checks. Every error names file, key and the
allowed range in one line."""

import copy
from dataclasses import fields
from pathlib import Path

import yaml

from .atomic import atomic_path
from .forms.objective import FormParams, ObjectiveError, build_objective
from .rig.biaxial import BiaxialParams
from .rig.deposition import ROLLING_COEFFICIENTS
from .rig.params import RigParams
from .schema import ConfigError, fill_defaults, load_schema, load_yaml, schema_path, validate  # noqa: F401 (re-exported)
from .seeds import job_seed  # noqa: F401 (re-exported: the workflow's rules take it from here)



def jobs_config_file(cfg, path, write=True):
    """Where the workflow's jobs read their config when it comes from several files
    (--configfile A B ...) or with --config KEY=VALUE: ``cfg``, the config Snakemake made of
    them, written to ``path`` (only when it differs from what the file holds) - a job reads
    one file. Returns ``path``."""
    text = yaml.safe_dump(cfg, sort_keys=False)
    path = Path(path)
    if write and (not path.is_file() or path.read_text() != text):
        with atomic_path(path) as tmp:
            tmp.write_text(text)
    return str(path)


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
    # a settled pile's surface still moves at about the settle speed: a plate lowered no
    # faster follows it down and never lands (rig.assembly.settle_plate)
    ("rig.box.assembly", "settle_speed_m_s", "plate_settle_velocity_m_s", True),
    ("rig.biaxial.loading", "deviator_min_kPa", "deviator_max_kPa", True),
    ("bpm", "radius_min_mm", "radius_max_mm", False),
)

# stages that run a specimen set, and the rig its set must be (None: the targets decide,
# calibration.cli.targets_kind)
SPECIMEN_STAGES = (("measured.sim", "biaxial"), ("calibration", None), ("loop", "biaxial"),
                   ("parametric", "box"), ("strength", "biaxial"))


def _section(cfg, dotted):
    for part in dotted.split("."):
        cfg = (cfg or {}).get(part) or {}
    return cfg


def stage_default(section, key):
    """The value a stage uses for a key the config leaves out (its params class' default)."""
    if section == "bpm":        # the schema gives the bpm section's defaults (= BpmParams')
        return load_schema("config")["properties"]["bpm"]["properties"][key].get("default")
    cls = BiaxialParams if section.startswith("rig.biaxial") else RigParams
    return {f.name: f.default for f in fields(cls)}.get(key)


def check_domain(cfg, file):
    """Checks across keys that a schema cannot state (on the values the stages will use,
    defaults included); ConfigError naming key and range."""
    for section, lo_key, hi_key, strict in ORDERED_PAIRS:
        sec = _section(cfg, section)
        lo, hi = (sec.get(k, stage_default(section, k)) for k in (lo_key, hi_key))
        if lo is not None and hi is not None and not (lo < hi if strict else lo <= hi):
            relation = "below" if strict else "at most"
            raise ConfigError(file, f"{section}.{lo_key}",
                              f"{lo:g} must be {relation} {section}.{hi_key} ({hi:g})")
    loads = _section(cfg, "rig.box.loading").get("static_loads_kN") or []
    if any(b <= a for a, b in zip(loads, loads[1:])):
        raise ConfigError(file, "rig.box.loading.static_loads_kN", f"{loads} must increase step by step")
    check_rolling(cfg, file)
    check_specimen_sets(cfg, file)
    check_stress_mapping(cfg, file)
    return cfg


def check_rolling(cfg, file):
    """The rolling_* coefficients only act with the law's rolling sub-model: given without
    ``rolling_resistance: epsd`` they would do nothing, so they are refused."""
    for rig in ("box", "biaxial"):
        section = f"rig.{rig}.assembly"
        sec = _section(cfg, section)
        if sec.get("rolling_resistance", "none") != "none":
            continue
        for key in ROLLING_COEFFICIENTS:
            if key in sec:
                raise ConfigError(file, f"{section}.{key}", f"{sec[key]!r} does nothing with "
                                  f"{section}.rolling_resistance none; allowed: rolling_resistance "
                                  "epsd, or leave the key out")


def check_specimen_sets(cfg, file):
    """Each stage names a specimen set of the rig it runs and takes at most its cases; a
    box set has the box rig's size. ConfigError naming the key otherwise."""
    sets = cfg.get("specimens") or {}
    for name, s in sets.items():
        for key in ("width_m", "height_m"):
            if s["rig"] == "box" and s.get(key) is not None:
                raise ConfigError(file, f"specimens.{name}.{key}", f"{s[key]:g}: a box set has "
                                  "rig.box.assembly's size; allowed: null (or leave it out)")
    for section, kind in SPECIMEN_STAGES:
        stage = _section(cfg, section)
        name = stage.get("specimens")
        if name is None:
            continue
        if name not in sets:
            raise ConfigError(file, f"{section}.specimens", f"{name!r} is not a specimen set; "
                              f"allowed: {', '.join(sets) or 'a set defined under specimens'}")
        if kind and sets[name]["rig"] != kind:
            raise ConfigError(file, f"{section}.specimens", f"{name!r} is a {sets[name]['rig']} "
                              f"set; allowed: a {kind} set")
        if stage.get("cases", 0) > sets[name]["cases"]:
            raise ConfigError(file, f"{section}.cases", f"{stage['cases']}, but the set {name!r} "
                              f"has {sets[name]['cases']}; allowed: at most {sets[name]['cases']}")


def unknown_set_databases(cfg, databases):
    """One line per specimen set whose database the databases file does not define: a note,
    not an error - a study of other databases runs, only the stages using the set cannot."""
    return [f"note: specimens.{name}.database {s['database']!r} is not in {cfg['databases_file']}: "
            f"the stages that use the set cannot run" for name, s in (cfg.get("specimens") or {}).items()
            if s["database"] not in databases]


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


def database_seed(study_seed, name, definition):
    """One deterministic seed per database: explicit, or job_seed(study seed, name)."""
    if definition.get("seed") is not None:
        return int(definition["seed"])
    return job_seed(study_seed, name)


def check_stress_mapping(cfg, file):
    """The ``stress_mapping`` section's checks across keys (the schema checks each value):
    ConfigError naming file and key. Returns the section, ``kind`` filled."""
    sec = dict(cfg.get("stress_mapping") or {})
    sec.setdefault("kind", "none")
    if sec["kind"] == "none":
        return sec
    env = sec.get("lab_envelope") or {}
    key = "stress_mapping.lab_envelope"
    if not (env.get("citation") or "").strip():
        raise ConfigError(file, f"{key}.citation", f"empty; {sec['kind']} needs the envelope's "
                          "source (large triaxial tests on the material)")
    p, q = env.get("confining_pressure_kPa") or [], env.get("peak_deviator_kPa") or []
    if not p:
        raise ConfigError(file, f"{key}.confining_pressure_kPa", "empty; allowed: one or more "
                          "confining pressures [kPa], increasing")
    if len(q) != len(p):
        raise ConfigError(file, f"{key}.peak_deviator_kPa", f"{len(q)} values; allowed: one per "
                          f"confining_pressure_kPa ({len(p)})")
    if any(b <= a for a, b in zip(p, p[1:])):
        raise ConfigError(file, f"{key}.confining_pressure_kPa", f"{p}: must increase")
    return sec
