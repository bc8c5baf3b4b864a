"""Sphinx extension: the reference pages written from the code at every build, one source
each, so they cannot drift from it: the config keys from the config schema (the rig keys'
defaults from the rigs' parameter classes, which the stages use), the loop's effects and
the calibration's material parameters from the modifiers' registry, the contact
sub-models from theirs, a case's per-cycle variables from the metrics writer's table, the
Snakemake targets from the rules' docstrings.
Written into reference/generated/ (not kept in git) before Sphinx reads the sources."""
import re
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


def modifiers_page():
    lines = ["# Effects and material parameters", "",
             "The registry of modifiers (`ballaststudy.scenario.modifiers`): the material "
             "parameters a calibration varies and the effects the loop chooses among.", ""]
    for role, title in (("material", "Material parameters"), ("effect", "Effects")):
        lines += [f"## {title}", ""]
        for name, m in MODIFIERS.items():
            if m.role != role:
                continue
            lines += [f"### `{name}`", "", _cell(m.mechanism), "",
                      "| parameter | long name | units | low | high |", "|---|---|---|---|---|"]
            lines += [f"| `{p.name}` | {_cell(p.long_name)} | {_cell(p.units)} | {p.low:g} | {p.high:g} |"
                      for p in m.parameters]
            lines.append("")
    return "\n".join(lines)


def submodels_page():
    lines = ["# Contact sub-models", "",
             "A contact law is one sub-model per kind (normal, damping, tangential, rolling), "
             "registered in `ballaststudy.dem.law`; their coefficients are columns of the "
             "per-material-pair table ([contact laws](../../explanation/contact-laws.md)).", ""]
    for kind in KINDS:
        lines += [f"## {kind}", "", "| sub-model | coefficients | history columns | state | law |",
                  "|---|---|---|---|---|"]
        lines += [f"| `{sm.name}` | {', '.join(f'`{c}`' for c in sm.coefficients) or '-'} | {sm.history} | "
                  f"{', '.join(sm.state) or '-'} | {_cell(sm.doc)} |"
                  for (k, _), sm in SUBMODELS.items() if k == kind]
        lines.append("")
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
    for name, text in pages.items():
        path = GENERATED / name
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)


def setup(app):
    app.connect("builder-inited", write_pages)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
