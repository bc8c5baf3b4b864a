"""Sphinx extension: the reference pages written from the code at every build, one source
each, so they cannot drift from it: the config keys from the config schema (the rig keys'
defaults from the rigs' parameter classes, which the stages use), the loop's effects and
the calibration's material parameters from the modifiers' registry, the contact
sub-models from theirs, a case's per-cycle variables from the metrics writer's table, the
Snakemake targets from the rules' docstrings.
Written into reference/generated/ (not kept in git) before Sphinx reads the sources."""
import re
import sys
from pathlib import Path

from ballaststudy.config import stage_default
from ballaststudy.dem.law import KINDS, SUBMODELS
from ballaststudy.metrics.output import VARIABLES
from ballaststudy.scenario.modifiers import MODIFIERS
from ballaststudy.schema import allowed, load_schema

GENERATED = Path(__file__).resolve().parents[1] / "reference" / "generated"
STAGE_SECTIONS = ("rig.box", "rig.biaxial")     # their defaults: the rigs' parameter classes


def _cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def _toctree(title, entries):
    """A section titled ``title`` listing the pages ``entries``."""
    return [f"## {title}", "", "```{toctree}", ":maxdepth: 1", "", *entries, "```", ""]


def _is_leaf(node):
    return "properties" not in node


def config_sections(schema, path=""):
    """[(dotted section, its description, [(key, leaf schema)])] depth first."""
    leaves, below = [], []
    for key, node in schema.get("properties", {}).items():
        dotted = f"{path}{key}"
        if _is_leaf(node):
            leaves.append((key, node))
        else:
            below += config_sections(node, dotted + ".")
    here = [(path.rstrip("."), schema.get("description", ""), leaves)] if leaves else []
    return here + below


def _default(section, key, node):
    if "default" in node or not section.startswith(STAGE_SECTIONS):
        value = node.get("default", "")
    else:
        value = stage_default(section, key)
    return "" if value == "" else f"`{value!r}`" if not isinstance(value, str) else f"`{value}`"


def config_page():
    lines = ["# Configuration keys", "",
             "Every key of `config/config.yaml`, from the schema that validates it "
             "(`src/ballaststudy/schemas/config.schema.yaml`). A key left out takes its default. "
             "Units are SI unless the key's name carries one (`_mm`, `_kPa`, `_kN`, ...); "
             "the description ends with it.", ""]
    for section, description, leaves in config_sections(load_schema("config")):
        lines += [f"## `{section or 'top level'}`", "", _cell(description), "",
                  "| key | default | allowed | description |", "|---|---|---|---|"]
        lines += [f"| `{key}` | {_cell(_default(section, key, node))} | {_cell(allowed(node))} | "
                  f"{_cell(node.get('description', ''))} |" for key, node in leaves]
        lines.append("")
    return "\n".join(lines)


def _effect_module_doc(m):
    """The docstring of the module that defines an effect (its physics, in words)."""
    for fn in (m.configure, m.hook, m.off):
        module = sys.modules.get(getattr(fn, "__module__", None) or "")
        if module is not None and module.__name__.rsplit(".", 1)[-1] != "material" and module.__doc__:
            return " ".join(module.__doc__.split())
    return ""


def _restrictions(m):
    found = [text for flag, text in (
        (m.needs_flat_joints, "needs flat joints: refused with rigid stones"),
        (m.needs_splitting, "acts on splitting stones: needs `stone_model: rigid` with `rigid_stones.splitting: true`"),
        (m.needs_rolling, "sets a rolling coefficient: the specimens must be assembled with `rolling_resistance: epsd`"),
        (m.covariate is not None, f"acts only through the test's covariate `{m.covariate}`: tests without it cannot show it"),
        (m.hook_only, "acts from the end of the first loading on (an end-of-cycle hook): its runs share the plain model's first loading"),
    ) if flag]
    return found or ["none"]


def modifier_page(name, m):
    no_effect = m.off({}) if m.off else None
    lines = [f"# `{name}`", "", _cell(m.mechanism), ""]
    doc = _effect_module_doc(m) if m.role == "effect" else ""
    if doc:
        lines += [doc, ""]
    usage = (f"`loop.effects: [..., {name}]`, or `ballaststudy case run ... --effect {name}:"
             + ",".join(f"{p.name}=VALUE" for p in m.parameters) + "`") if m.role == "effect" else \
        f"`calibration.parameters: {{{name}: {{min: ..., max: ...}}}}`"
    lines += ["## Syntax", "", usage, "", "## Parameters", "",
              "| parameter | long name | units | low | high | no-effect value |", "|---|---|---|---|---|---|"]
    lines += [f"| `{p.name}` | {_cell(p.long_name)} | {_cell(p.units)} | {p.low:g} | {p.high:g} | "
              f"{'-' if no_effect is None else _cell(no_effect.get(p.name, '-'))} |" for p in m.parameters]
    lines += ["", "## Restrictions", ""] + [f"- {r}" for r in _restrictions(m)]
    return "\n".join(lines) + "\n"


def modifiers_page():
    lines = ["# Effects and material parameters", "",
             "The registry of modifiers (`ballaststudy.scenario.modifiers`): the material "
             "parameters a calibration varies and the effects the loop chooses among, one page "
             "each.", ""]
    for role, title in (("material", "Material parameters"), ("effect", "Effects")):
        lines += _toctree(title, [f"modifiers/{n}" for n, m in MODIFIERS.items() if m.role == role])
    return "\n".join(lines)


def submodel_page(sm):
    lines = [f"# `{sm.name}` ({sm.kind})", "", _cell(sm.doc), "",
             "## Syntax", "",
             f"`ContactLaw(..., {sm.kind}=\"{sm.name}\")` picks it for the {sm.kind} part of a contact law "
             "(`ballaststudy.dem.law`); its coefficients are set per material pair with "
             "`Simulation.set_contact_coefficient(name, value, material_a, material_b)`.", "",
             "## Coefficients", ""]
    lines += [f"- `{c}`" for c in sm.coefficients] or ["none"]
    lines += ["", "## State", "", f"History columns (reset when the contact opens): {sm.history}; "
              f"persistent per-contact state: {', '.join(sm.state) or 'none'}. Both are checkpointed.", "",
              "The equations: [the physics](../../../explanation/physics.md)."]
    return "\n".join(lines) + "\n"


def submodels_page():
    lines = ["# Contact sub-models", "",
             "A contact law is one sub-model per kind (normal, damping, tangential, rolling), "
             "registered in `ballaststudy.dem.law`; their coefficients are columns of the "
             "per-material-pair table ([contact laws](../../explanation/contact-laws.md)), one page each.", ""]
    for kind in KINDS:
        lines += _toctree(kind, [f"submodels/{kind}-{sm.name}" for (k, _), sm in SUBMODELS.items() if k == kind])
    return "\n".join(lines)


def metrics_page():
    lines = ["# A case's per-cycle variables", "",
             "`metrics.nc` of every case: one row per load cycle (dimension `cycle`), each "
             "variable with these `units` and `long_name` attributes (`study.nc` holds the "
             "behaviours the study reads, over database x case x cycle).", "",
             "| variable | units | long_name |", "|---|---|---|"]
    lines += [f"| `{name}` | {_cell(units)} | {_cell(long_name)} |" for name, (units, long_name, _) in VARIABLES.items()]
    return "\n".join(lines) + "\n"


WORKFLOW = Path(__file__).resolve().parents[2]


def workflow_rules():
    """[(rule, file, its docstring)] in the order workflow/Snakefile and workflow/rules/*.smk
    define them (`snakemake --list-rules` prints the same docstrings)."""
    files = [WORKFLOW / "workflow" / "Snakefile", *sorted((WORKFLOW / "workflow" / "rules").glob("*.smk"))]
    return [(m.group(1), path.relative_to(WORKFLOW).as_posix(), " ".join(m.group(2).split()))
            for path in files for m in re.finditer(r'(?m)^rule (\w+):\n\s+"""(.*?)"""', path.read_text(), re.S)]


def rules_page():
    lines = ["# Snakemake targets", "",
             "Every rule of the workflow, by its docstring (`snakemake --list-rules` prints the "
             "same): name one to run it and what it needs, `snakemake --cores 2 <rule>`; `all` "
             "is the default job.", "", "| rule | defined in | what it makes |", "|---|---|---|"]
    lines += [f"| `{name}` | `{path}` | {_cell(doc)} |" for name, path, doc in workflow_rules()]
    return "\n".join(lines) + "\n"


def write_pages(app=None):
    """Write the generated pages (only those whose text changed, so Sphinx rebuilds no more)."""
    GENERATED.mkdir(parents=True, exist_ok=True)
    pages = {"config.md": config_page(), "modifiers.md": modifiers_page(), "submodels.md": submodels_page(),
             "metrics.md": metrics_page(), "rules.md": rules_page()}
    pages.update({f"modifiers/{n}.md": modifier_page(n, m) for n, m in MODIFIERS.items()})
    pages.update({f"submodels/{sm.kind}-{sm.name}.md": submodel_page(sm) for sm in SUBMODELS.values()})
    for name, text in pages.items():
        path = GENERATED / name
        path.parent.mkdir(exist_ok=True)
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)


def setup(app):
    app.connect("builder-inited", write_pages)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
