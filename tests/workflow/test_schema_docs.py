"""The config schema documents every key: each leaf has a description, and a key whose name
ends in a unit suffix names that unit in square brackets in it. No YAML file of the schemas
or the configs repeats a key in a mapping (PyYAML would silently keep the last one)."""
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = ROOT / "src" / "ballaststudy" / "schemas" / "config.schema.yaml"
YAML_FILES = sorted((ROOT / "src" / "ballaststudy" / "schemas").glob("*.yaml")) + sorted(
    (ROOT / "config").glob("*.yaml"))

# key-name suffix -> the unit as the description writes it (in square brackets); the
# longest suffix a key ends in decides (_m_s_per_kN before _kN, _1_s and _m_s before _s)
UNITS = {
    "_m": "m",
    "_mm": "mm",
    "_m_s": "m/s",
    "_m_s2": "m/s^2",
    "_kg_m3": "kg/m^3",
    "_1_s": "1/s",
    "_m_s_per_kN": "m/s per kN",
    "_m_s_per_kPa": "m/s per kPa",
    "_N": "N",
    "_kN": "kN",
    "_Pa": "Pa",
    "_kPa": "kPa",
    "_Hz": "Hz",
    "_GB": "GB",
    "_min": "min",
    "_s": "s",
    "_steps": "steps",
}
# names whose suffix is not a unit (forms.cb_ratio_min: the smallest c/b, not minutes)
NOT_UNITS = {"cb_ratio_min"}


def leaves(node, path=()):
    """(dotted path, schema) of every leaf under ``node``: a node without ``properties`` (and
    without an ``additionalProperties`` schema that has them; its keys are named ``*``)."""
    props = node.get("properties")
    extra = node.get("additionalProperties")
    extra = extra if isinstance(extra, dict) and "properties" in extra else None
    if props is None and extra is None:
        yield ".".join(path), node
        return
    for key, sub in (props or {}).items():
        yield from leaves(sub, path + (key,))
    if extra is not None:
        yield from leaves(extra, path + ("*",))


def unit_of(name):
    """The unit a key's name ends in (None: no unit suffix)."""
    if name in NOT_UNITS:
        return None
    ends = [s for s in UNITS if name.endswith(s)]
    return UNITS[max(ends, key=len)] if ends else None


@pytest.fixture(scope="module")
def schema_leaves():
    with open(SCHEMA, encoding="utf-8") as f:
        return list(leaves(yaml.safe_load(f)))


def test_walk_finds_the_leaves(schema_leaves):
    paths = {p for p, _ in schema_leaves}
    assert len(paths) == len(schema_leaves) > 200
    assert {"seed", "rig.box.assembly.width_m", "rig.biaxial.loading.frequency_Hz",
            "specimens.*.width_m", "calibration.parameters.*.min"} <= paths
    assert "rig.box.assembly" not in paths and "specimens" not in paths


def test_every_leaf_key_has_a_description(schema_leaves):
    lacking = [p for p, node in schema_leaves
               if not isinstance(node.get("description"), str) or not node["description"].strip()]
    assert not lacking, (f"{len(lacking)} of {len(schema_leaves)} leaf keys of {SCHEMA.name} "
                         "have no description:\n  " + "\n  ".join(lacking))


def test_unit_suffixes_cover_the_schema(schema_leaves):
    """Each suffix in UNITS is one that a key of the schema ends in (no dead entries)."""
    names = {p.rsplit(".", 1)[-1] for p, _ in schema_leaves}
    used = {max((s for s in UNITS if n.endswith(s)), key=len) for n in names - NOT_UNITS
            if any(n.endswith(s) for s in UNITS)}
    assert used == set(UNITS), f"suffixes no key ends in: {sorted(set(UNITS) - used)}"
    assert NOT_UNITS <= names


def test_unit_keys_name_their_unit(schema_leaves):
    wrong = []
    for path, node in schema_leaves:
        unit = unit_of(path.rsplit(".", 1)[-1])
        if unit is not None and f"[{unit}]" not in str(node.get("description", "")):
            wrong.append(f"{path}: [{unit}] not in {node.get('description')!r}")
    assert not wrong, "unit keys whose description lacks the unit:\n  " + "\n  ".join(wrong)


def test_unit_of():
    assert unit_of("width_m") == "m"
    assert unit_of("radius_min_mm") == "mm"
    assert unit_of("servo_gain_m_s_per_kN") == "m/s per kN"
    assert unit_of("tamping_velocity_m_s") == "m/s"
    assert unit_of("consolidation_strain_rate_max_1_s") == "1/s"
    assert unit_of("connect_timeout_s") == "s"
    assert unit_of("strength_sigma0_Pa") == "Pa"
    assert unit_of("deviator_max_kPa") == "kPa"
    assert unit_of("cb_ratio_min") is None
    assert unit_of("damping") is None


class UniqueKeyLoader(yaml.SafeLoader):
    """A SafeLoader that refuses a mapping with a key twice."""


def _unique_mapping(loader, node, deep=False):
    seen = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise yaml.constructor.ConstructorError(
                "while constructing a mapping", node.start_mark,
                f"key {key!r} repeated (first at line {seen[key] + 1})", key_node.start_mark)
        seen[key] = key_node.start_mark.line
    return loader.construct_mapping(node, deep=deep)


UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _unique_mapping)


def test_unique_key_loader_refuses_a_repeated_key():
    assert yaml.load("a: 1\nb: {c: 2}\n", Loader=UniqueKeyLoader) == {"a": 1, "b": {"c": 2}}
    with pytest.raises(yaml.constructor.ConstructorError, match="'c' repeated"):
        yaml.load("a: 1\nb:\n  c: 2\n  c: 3\n", Loader=UniqueKeyLoader)
    with pytest.raises(yaml.constructor.ConstructorError, match="'a' repeated"):
        yaml.load("a: {x: 1, a: 2}\na: 3\n", Loader=UniqueKeyLoader)


def test_yaml_files_found():
    names = {p.name for p in YAML_FILES}
    assert {"config.schema.yaml", "config.yaml", "thesis.yaml"} <= names


@pytest.mark.parametrize("path", YAML_FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_no_repeated_keys(path):
    with open(path, encoding="utf-8") as f:
        yaml.load(f, Loader=UniqueKeyLoader)
