"""Fuzz suite for the YAML inputs: every leaf key of the config, databases and measured-test
schemas gets each bad value (NaN, +Inf, -Inf, negative, zero, huge, wrong type, missing,
misspelled) through `ballaststudy config check`, which reads all three the way the workflow
does. Each try must exit 2 with one line naming the file (and, for an illegal value, the key),
or exit 0 if the value is legal; never a traceback, never exit 0 with an illegal value.

The oracle is the leaf's own subschema (plus: numbers finite, integers not floats), read
independently of the program's validation path; the program also applies cross-key rules and
builds every database's objective, so a legal leaf value may still be refused — in one line.
"""

import copy
import math
import random
from pathlib import Path

import jsonschema
import pytest
import yaml

from ballaststudy.cli import main
from ballaststudy.schema import load_schema

REPO = Path(__file__).resolve().parents[2]
SEED = 20261123
DATABASES = ("G_1-1", "box_test")     # a cheap subset: every schema leaf is still reached
BAD_KINDS = ("nan", "+inf", "-inf", "negative", "zero", "huge", "wrong type", "missing", "misspelled")

MEASURED_TEST = {
    "source": "synthetic test of the fuzz suite", "rig": "triaxial",
    "specimen": {"diameter_m": 0.3, "height_m": 0.6}, "confining_pressure_kPa": 30.0,
    "deviator_min_kPa": 10.0, "deviator_max_kPa": 230.0, "frequency_Hz": 10.0,
    "covariates": {"VCI": {"value": 10.0, "units": "%"}},
    "curves": [{"file": "curve.csv", "quantity": "axial_strain", "units": "%",
                "sign": "compression_positive"}],
}


# ------------------------------------------------------------------ leaves and the oracle


def _is_container(s):
    return s.get("type") == "object" or "properties" in s


def leaves(schema, instance, path=()):
    """(path, leaf subschema, parent subschema) for every leaf key; keys of free-named maps
    (databases, materials, covariates) are taken from the instance; list leaves also as [0]."""
    props = schema.get("properties", {})
    extra = schema.get("additionalProperties")
    named = list(props.items())
    if isinstance(extra, dict) and instance:
        named.append((next(iter(instance)), extra))
    for key, sub in named:
        value = (instance or {}).get(key)
        if _is_container(sub):
            yield from leaves(sub, value, path + (key,))
            continue
        yield path + (key,), sub, schema
        if isinstance(value, list) and value and isinstance(sub.get("items"), dict):
            yield path + (key, 0), sub["items"], None


def _types(s):
    t = s.get("type", [])
    out = set([t] if isinstance(t, str) else t)
    for alt in s.get("oneOf", []) + s.get("anyOf", []):
        out |= _types(alt)
    if "enum" in s:
        out |= {type(v).__name__ for v in s["enum"]}
    return out


def _finite(v):
    if isinstance(v, float):
        return math.isfinite(v)
    if isinstance(v, list):
        return all(map(_finite, v))
    if isinstance(v, dict):
        return all(map(_finite, v.values()))
    return True


def legal(leaf, value):
    """Is `value` allowed by the leaf's own subschema (numbers finite, integers not floats)?"""
    if isinstance(value, float) and "number" not in _types(leaf):
        return False
    return _finite(value) and jsonschema.Draft202012Validator(leaf).is_valid(value)


def bad_value(kind, leaf):
    integer = "integer" in _types(leaf) and "number" not in _types(leaf)
    numeric = _types(leaf) & {"integer", "number", "boolean", "array", "null"}
    return {"nan": math.nan, "+inf": math.inf, "-inf": -math.inf,
            "negative": -1 if integer else -1.5, "zero": 0 if integer else 0.0,
            "huge": 10**30 if integer else 1e300,
            "wrong type": "ten" if numeric else [1, 2]}[kind]


def misspelled(key, rng):
    """A typo: two neighbouring letters swapped (or a letter doubled in a short key)."""
    if len(key) < 4:
        return key + key[-1]
    i = rng.randrange(1, len(key) - 2)
    typo = key[:i] + key[i + 1] + key[i] + key[i + 2:]
    return typo if typo != key else key + key[-1]


# ------------------------------------------------------------------ files


@pytest.fixture(scope="module")
def originals(tmp_path_factory):
    """(config, databases, measured test) as dicts: the shipped config and databases (a subset
    of the databases), a synthetic measured test; paths in the config point at tmp files."""
    root = tmp_path_factory.mktemp("fuzz")
    cfg = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    dbs = yaml.safe_load((REPO / "config" / "databases.yaml").read_text())
    dbs["databases"] = {k: dbs["databases"][k] for k in DATABASES}
    cfg.update(databases_file=str(root / "databases.yaml"), databases=list(DATABASES))
    cfg["measured"].update(tests_dir=str(root / "measured"), data_dir=str(root / "data"))
    cfg["calibration"]["targets"] = ["t"]          # the synthetic test
    return root, cfg, dbs, copy.deepcopy(MEASURED_TEST)


def _set(data, path, value):
    for p in path[:-1]:
        data = data.setdefault(p, {}) if isinstance(p, str) else data[p]
    data[path[-1]] = value


def _dump(data):
    return yaml.dump(data, Dumper=getattr(yaml, "CSafeDumper", yaml.SafeDumper), sort_keys=False)


def _write(root, cfg, dbs, test):
    (root / "measured").mkdir(exist_ok=True)
    (root / "config.yaml").write_text(_dump(cfg))
    (root / "databases.yaml").write_text(_dump(dbs))
    (root / "measured" / "t.yaml").write_text(_dump(test))


def _dotted(path):
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def mutations(schema, instance, rng):
    """(path, kind, new instance, legal?, key the message must name) for every leaf x kind."""
    for path, leaf, parent in leaves(schema, instance):
        for kind in BAD_KINDS:
            data = copy.deepcopy(instance)
            if kind in ("missing", "misspelled"):
                if parent is None or not _has(data, path):
                    continue
                value = _pop(data, path)
                if kind == "missing":
                    yield path, kind, data, path[-1] not in parent.get("required", []), _dotted(path)
                elif parent.get("additionalProperties") is False:
                    typo = misspelled(path[-1], rng)
                    _set(data, path[:-1] + (typo,), value)
                    yield path, kind, data, False, _dotted(path[:-1] + (typo,))
                continue
            value = bad_value(kind, leaf)
            _set(data, path, value)
            yield path, kind, data, legal(leaf, value), _dotted(path)


def _has(data, path):
    for p in path:
        if not isinstance(data, (dict, list)) or (isinstance(data, dict) and p not in data):
            return False
        data = data[p]
    return True


def _pop(data, path):
    for p in path[:-1]:
        data = data[p]
    return data.pop(path[-1])


# ------------------------------------------------------------------ the suite


def _check(capsys, root, file, kind, path, is_legal, key):
    rc = main(["config", "check", "--config", str(root / "config.yaml")])
    out, err = capsys.readouterr()
    where = f"{file.name}: {_dotted(path)} = {kind}: rc {rc}, stderr {err!r}"
    assert "Traceback" not in out + err, where
    assert rc in (0, 2), where
    if rc == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("ballaststudy: error: "), where
        assert str(file.name) in lines[0], where
    if not is_legal:
        assert rc == 2 and key in err, where


def test_fuzz_every_leaf_key(originals, capsys, fuzz_report):
    root, cfg, dbs, test = originals
    (root / "data").mkdir(exist_ok=True)
    (root / "data" / "curve.csv").write_text("1, 0.1\n10, 0.2\n100, 0.3\n")
    _write(root, cfg, dbs, test)
    assert main(["config", "check", "--config", str(root / "config.yaml")]) == 0, capsys.readouterr()
    capsys.readouterr()
    rng = random.Random(SEED)
    counts = {}
    for name, schema_name, base in (("config.yaml", "config", cfg), ("databases.yaml", "databases", dbs),
                                    ("t.yaml", "measured", test)):
        file = root / ("measured/" + name if name == "t.yaml" else name)
        tried = refused = 0
        for path, kind, data, is_legal, key in mutations(load_schema(schema_name), base, rng):
            files = {"config": (data, dbs, test), "databases": (cfg, data, test),
                     "measured": (cfg, dbs, data)}[schema_name]
            _write(root, *files)
            _check(capsys, root, file, kind, path, is_legal, key)
            tried += 1
            refused += not is_legal
        counts[name] = (tried, refused)
    _write(root, cfg, dbs, test)
    fuzz_report.append("YAML fuzz, (key, bad value) pairs tried (of which illegal, all refused in one line "
                       "naming file and key; the legal rest accepted or refused in one line): "
                       + ", ".join(f"{f} {n} ({bad})" for f, (n, bad) in counts.items()))
    assert counts["config.yaml"][0] > 1000 and counts["databases.yaml"][0] > 100 and counts["t.yaml"][0] > 100


@pytest.mark.parametrize("schema_name", ["config", "databases", "measured"])
def test_every_number_has_a_range(schema_name):
    """Every numeric leaf states both bounds, so 'huge' is refused and every message says the range."""
    base = {"config": {}, "databases": {"databases": {"x": {}}}, "measured": {"covariates": {"x": {}}}}
    unbounded = []
    for path, leaf, _ in leaves(load_schema(schema_name), base[schema_name]):
        subs = [leaf] + leaf.get("oneOf", []) + ([leaf["items"]] if isinstance(leaf.get("items"), dict) else [])
        for s in subs:
            direct = {s["type"]} if isinstance(s.get("type"), str) else set(s.get("type", []))
            if direct & {"number", "integer"} and not (
                    {"minimum", "exclusiveMinimum"} & set(s) and {"maximum", "exclusiveMaximum"} & set(s)):
                unbounded.append(_dotted(path))
    assert not unbounded, unbounded
