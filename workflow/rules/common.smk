# Helpers shared by the rule files (the Snakemake workflow template's common.smk).
import json
from pathlib import Path

from ballaststudy.config import stage_default
from ballaststudy.measured.importer import load_conditions
from ballaststudy.scenario.scenario import conditioned_keys as _conditioned_keys


def section(dotted):
    """The config's section at a dotted path ("rig.biaxial.loading"), {} where absent."""
    node = config
    for part in dotted.split("."):
        node = (node or {}).get(part) or {}
    return node


def trigger(*dotted, drop=()):
    """A rule's rerun trigger: the JSON of config sections (Snakemake reruns a job whose
    params changed), keys in ``drop`` left out - the keys the stage overrides, whose edits
    must rerun nothing. One section: its JSON as it is; several: {path: section}."""
    parts = {d: {k: v for k, v in section(d).items() if k not in drop} if isinstance(section(d), dict)
             else section(d) for d in dotted}
    return json.dumps(parts[dotted[0]] if len(dotted) == 1 else parts, sort_keys=True)


def box_assembly_trigger():
    """The box assembly's rerun trigger: its section, and the loading's control_every where
    it is not its default - the plate is lowered onto the stones in moves of that many
    steps, so it shapes the specimen (at the default the trigger is the section alone, as
    it was before control_every was read here)."""
    every = section("rig.box.loading").get("control_every")
    if every in (None, stage_default("rig.box.loading", "control_every")):
        return trigger("rig.box.assembly")
    return json.dumps({"assembly": section("rig.box.assembly"), "plate_moves_steps": every}, sort_keys=True)


def stones_trigger():
    """The stone model's rerun trigger: its name, and how its stones split when they do
    (a run whose stones do not split keeps the trigger it had before splitting existed)."""
    if not (config.get("rigid_stones") or {}).get("splitting"):
        return trigger("stone_model")
    return trigger("stone_model", "rigid_stones")


def conditioned_keys(kind, tests):
    """The rig parameters every measured test of ``tests`` (names under measured.tests_dir)
    sets itself: edited in the config, they change nothing the stage runs. Tests that are
    not there (no measured tests: the stage cannot run) decide nothing."""
    tests_dir = Path(config["measured"]["tests_dir"])
    return _conditioned_keys(kind, [load_conditions(tests_dir / f"{t}.yaml") for t in tests
                                    if (tests_dir / f"{t}.yaml").is_file()])


SPECIMENS = config.get("specimens") or {}


def specimen_files(stage):
    """The assembled specimens a stage (its dotted section, with ``specimens`` and ``cases``)
    runs: the first ``cases`` of its set - a biaxial set's under results/specimens/<set>/
    (rule specimen_assemble), a box set's the study's assembled cases of its database."""
    sec = section(stage)
    name = sec["specimens"]
    s = SPECIMENS[name]
    if s["rig"] == "box":
        return [f"{RESULTS}/cases/{s['database']}/case{k}/assembled.nc" for k in range(sec["cases"])]
    return [f"{RESULTS}/specimens/{name}/case{k}.nc" for k in range(sec["cases"])]


# The stress mapping (config stress_mapping, scenario/mapping.py): strength_ratio reads the
# strength envelope of the specimen set a stage runs (strength.smk); none reads nothing.
MAPPED = (config.get("stress_mapping") or {}).get("kind", "none") != "none"


def mapping_input(stage):
    """The strength envelope a stage's stress mapping reads: its set's; [] for none and for a
    box set (box tests are loaded as measured)."""
    name = section(stage)["specimens"]
    return [f"{RESULTS}/strength/{name}/envelope.nc"] if MAPPED and SPECIMENS[name]["rig"] == "biaxial" else []


def mapping_option(stage):
    """The stage's command-line option for it ("" for none)."""
    files = mapping_input(stage)
    return f"--strength-envelope {files[0]}" if files else ""
