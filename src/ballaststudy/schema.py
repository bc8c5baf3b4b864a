"""Validation of the YAML files we read against the packaged JSON schemas, with one-line
messages: the file, the key, what was given and what is allowed.

Numbers must be finite (JSON has no NaN or Inf, but YAML's `.nan`/`.inf` slip through a
plain JSON-schema validator because NaN compares false with every bound), and integers must
be integers (`5.0` for a step count would reach `range()` and crash far from the file).
"""

import copy
import difflib
import functools
import math
from importlib import resources
from pathlib import Path

import jsonschema
import yaml


class ConfigError(ValueError):
    """Bad input: `file: key: message`."""

    def __init__(self, file, key, message):
        super().__init__(f"{file}: {key}: {message}" if key else f"{file}: {message}")
        self.file, self.key, self.message = str(file), key, message

    def __reduce__(self):           # raised in a worker process, re-raised in the parent
        return ConfigError, (self.file, self.key, self.message)


def schema_path(name):
    """Path of a packaged schema, e.g. schema_path('config')."""
    return Path(resources.files("ballaststudy") / "schemas" / f"{name}.schema.yaml")


def _is_number(checker, x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _is_integer(checker, x):
    return isinstance(x, int) and not isinstance(x, bool)


_TYPES = jsonschema.Draft202012Validator.TYPE_CHECKER.redefine_many(
    {"number": _is_number, "integer": _is_integer})
StrictValidator = jsonschema.validators.extend(jsonschema.Draft202012Validator, type_checker=_TYPES)


def inline_refs(node, root):
    """The schema with every local `$ref` replaced by its target (our schemas are not
    recursive), so each error's subschema describes itself."""
    if isinstance(node, dict):
        if "$ref" in node:
            target = root
            for part in node["$ref"].lstrip("#/").split("/"):
                target = target[part]
            rest = {k: v for k, v in node.items() if k != "$ref"}
            return inline_refs({**target, **rest}, root)
        return {k: inline_refs(v, root) for k, v in node.items() if k != "$defs"}
    if isinstance(node, list):
        return [inline_refs(v, root) for v in node]
    return node


@functools.cache
def _schema(name):
    raw = yaml.safe_load(schema_path(name).read_text())
    return inline_refs(raw, raw)


def load_schema(name):
    """The packaged schema `name`, refs inlined (a fresh copy)."""
    return copy.deepcopy(_schema(name))


# ------------------------------------------------------------------ what is allowed

_KIND = {"number": "a number", "integer": "an integer", "string": "text", "boolean": "true or false",
         "null": "null", "array": "a list", "object": "a mapping of keys"}


def _bounds(s):
    parts = []
    for key, op in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<")):
        if key in s:
            parts.append(f"{op} {s[key]:g}" if isinstance(s[key], float) else f"{op} {s[key]}")
    return " and ".join(parts)


def allowed(s):
    """A subschema in words, e.g. 'a number > 0 and <= 10', "one of 'box', 'biaxial'"."""
    if "enum" in s:
        return "one of " + ", ".join(repr(v) for v in s["enum"])
    alts = s.get("oneOf") or s.get("anyOf")
    if alts:
        return " or ".join(dict.fromkeys(allowed(a) for a in alts))
    types = s.get("type", [])
    types = [types] if isinstance(types, str) else types
    words = []
    for t in types:
        w = _KIND.get(t, t)
        if t in ("number", "integer") and _bounds(s):
            w += " " + _bounds(s)
        if t == "array":
            lo, hi = s.get("minItems"), s.get("maxItems")
            if lo is not None and lo == hi:
                w += f" of {lo} items"
            elif lo is not None or hi is not None:
                w += f" of {lo or 0} to {'any number of' if hi is None else hi} items"
            if isinstance(s.get("items"), dict):
                w += f" (each {allowed(s['items'])})"
        words.append(w)
    return " or ".join(words) or "see the schema"


def _given(x):
    if isinstance(x, float) and not math.isfinite(x):
        return f"{x!r} (not a finite number)"
    if isinstance(x, str) and _looks_numeric(x):
        return f"{x!r} (YAML reads it as text: write a decimal point, e.g. 1.0e+6)"
    text = repr(x)
    return text if len(text) <= 60 else text[:57] + "..."


def _looks_numeric(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


# ------------------------------------------------------------------ messages


def _key(path):
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _unknown_keys(error):
    s = error.schema
    known = list(s.get("properties", {}))
    unknown = [k for k in error.instance if k not in known]
    return unknown, known


def _message(error):
    """(key path, message) of one jsonschema error, in our words."""
    path, s, v = list(error.absolute_path), error.schema, error.validator
    if v == "additionalProperties":
        unknown, known = _unknown_keys(error)
        close = difflib.get_close_matches(str(unknown[0]), known, n=1, cutoff=0.6)
        hint = f"did you mean {close[0]!r}? " if close else ""
        return path + [unknown[0]], f"unknown key; {hint}allowed keys: {', '.join(known)}"
    if v == "required":
        missing = [k for k in s["required"] if k not in error.instance][0]
        return path + [missing], "missing (required)"
    if v == "oneOf":
        # a value of the right kind but out of range: report that, not the choice of kinds
        inner = [c for c in (error.context or []) if c.validator != "type"]
        if inner:
            return _message(max(inner, key=lambda c: len(c.absolute_path)))
    if v == "propertyNames":
        return path, f"{error.message}; allowed names: {allowed(s['propertyNames'])}"
    return path, f"{_given(error.instance)} is not allowed; allowed: {allowed(s)}"


def first_error(data, schema):
    """(key path, message) of the first error (shallowest key first; a missing key counts
    at its own depth, after a bad value written beside it: that is what the user typed), or None."""
    def order(e):
        missing = e.validator == "required"
        return len(e.absolute_path) + missing, missing, list(map(str, e.absolute_path))
    errors = sorted(StrictValidator(schema).iter_errors(data), key=order)
    return _message(errors[0]) if errors else None


def validate(data, schema_name, file):
    """Validate against a packaged schema, filling its defaults; raise ConfigError on the first error."""
    schema = _schema(schema_name)
    found = first_error(data, schema)
    if found:
        path, message = found
        raise ConfigError(file, _key(path), message)
    fill_defaults(data, schema)
    return data


def fill_defaults(data, schema):
    for key, sub in schema.get("properties", {}).items():
        if isinstance(sub, dict) and "default" in sub and key not in data:
            data[key] = copy.deepcopy(sub["default"])
        if isinstance(sub, dict) and isinstance(data.get(key), dict) and sub.get("type") == "object":
            fill_defaults(data[key], sub)


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """A mapping gives one key twice (dotted path, line numbers)."""

    def __init__(self, key, first, second):
        where = f"lines {first + 1} and {second + 1}" if first != second else f"line {first + 1}"
        super().__init__(problem=f"key given twice ({where}); keep one")
        self.key = key


class _UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):   # libyaml when present: ~10x faster
    """yaml.safe_load, except that a key given twice in one mapping is refused: PyYAML keeps
    the last one silently, so an edit to the first copy would do nothing.

    Checked on the node tree before construction: there the path to each mapping is known,
    and a merge (`<<: *base`) has not yet been flattened into the mapping (a key that
    overrides a merged one is not a duplicate)."""

    def construct_document(self, node):
        self._check_unique(node, [], set())
        return super().construct_document(node)

    def _check_unique(self, node, path, seen):
        if id(node) in seen:                         # an alias: checked where it is anchored
            return
        seen.add(id(node))
        if isinstance(node, yaml.SequenceNode):
            for i, item in enumerate(node.value):
                self._check_unique(item, path + [i], seen)
        elif isinstance(node, yaml.MappingNode):
            first = {}
            for key_node, value_node in node.value:
                sub = path
                if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
                    key = self.construct_object(key_node)    # `1` and `0x1` are one key
                    sub = path + [str(key)]
                    earlier = first.setdefault(key, key_node)
                    if earlier is not key_node:
                        raise DuplicateKeyError(_key(sub), earlier.start_mark.line, key_node.start_mark.line)
                self._check_unique(value_node, sub, seen)


def load_yaml(path):
    """A YAML file's data ({} if empty); ConfigError if missing, unreadable, not YAML text or
    a key is given twice in one mapping."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(path, None, "is a folder; expected a YAML file")
    if not path.is_file():
        raise ConfigError(path, None, "file not found")
    try:
        data = yaml.load(path.read_bytes().decode("utf-8"), Loader=_UniqueKeyLoader)
    except UnicodeDecodeError:
        raise ConfigError(path, None, "not a text file; expected YAML (UTF-8)") from None
    except DuplicateKeyError as err:
        raise ConfigError(path, err.key, err.problem) from None
    except yaml.YAMLError as err:
        where = getattr(err, "problem_mark", None)
        line = f"line {where.line + 1}: " if where else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise ConfigError(path, None, f"not valid YAML: {line}{problem}") from None
    except OSError as err:
        raise ConfigError(path, None, f"cannot be read: {err.strerror}") from None
    return {} if data is None else data
