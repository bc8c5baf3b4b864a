"""The user guide builds strictly: `sphinx-build -W` (every warning an error: a broken
cross-reference, a page in no table of contents, bad Markdown, a help text that is not
valid reStructuredText), with the reference pages written from the code at build time;
and every command, Snakemake target and config key the README and the guide name exists."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_guide_builds_without_warnings(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                          "-d", str(tmp_path / "doctrees"), str(ROOT / "docs"), str(tmp_path / "html")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-4000:]
    for page in ("index", "reference/cli", "reference/generated/config", "reference/generated/modifiers",
                 "reference/generated/submodels", "reference/generated/metrics", "reference/generated/rules"):
        assert (tmp_path / "html" / f"{page}.html").is_file(), page


# ------------------------------------------------------------- what the guide names exists

import re  # noqa: E402

from ballaststudy.cli import build_parser  # noqa: E402
from ballaststudy.schema import load_schema  # noqa: E402

FILE_SUFFIXES = {"nc", "yaml", "md", "png", "csv", "py", "json", "html", "log"}
VALUED = {"--cores", "-c", "-j", "--jobs", "--configfile", "--config", "--profile", "--report", "--forcerun",
          "-R", "--until", "--omit-from", "--slurm-status-command", "--slurm-init-seconds-before-status-checks"}


def guide_code():
    """{page: its code (inline spans, indented and fenced blocks)} of the README and the
    guide's hand-written pages."""
    pages = [ROOT / "README.md"] + [p for p in (ROOT / "docs").rglob("*.md")
                                    if "generated" not in p.parts and "parts" not in p.parts]
    code = {}
    for page in pages:
        text = page.read_text()
        blocks = re.findall(r"```[^\n]*\n(.*?)```", text, re.S) + re.findall(r"(?m)^(?: {4}|\t)(.+)$", text)
        spans = re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))
        code[page.relative_to(ROOT)] = blocks + spans
    return code


def commands_named(code):
    """[(page, ballaststudy argv)] of every `ballaststudy ...` command in the code."""
    return [(page, m.group(1).split()) for page, chunks in code.items() for chunk in chunks
            for m in re.finditer(r"\bballaststudy ((?:[a-z]+)(?: [a-z]+)?)", chunk)]


def subcommands(parser, prefix=()):
    out = {prefix}
    for action in parser._actions:
        if hasattr(action, "choices") and isinstance(action.choices, dict):
            for name, sub in action.choices.items():
                out |= subcommands(sub, prefix + (name,))
    return out


def test_every_command_the_guide_names_exists():
    """`ballaststudy forms frobnicate` fails; `ballaststudy loop results/...` passes (a
    command without subcommands takes what follows as arguments)."""
    known = subcommands(build_parser())
    groups = {k[:-1] for k in known if k}

    def exists(argv):
        return tuple(argv[:1]) in known and (tuple(argv[:1]) not in groups or tuple(argv[:2]) in known)
    named = commands_named(guide_code())
    wrong = [(str(page), " ".join(argv)) for page, argv in named if not exists(argv)]
    assert len(named) > 20 and not wrong, wrong


def snakemake_targets(code):
    """[(page, target)] named on `snakemake ...` command lines."""
    out = []
    for page, chunks in code.items():
        for chunk in chunks:
            for line in re.findall(r"\bsnakemake\b([^`\n;&|#]*)", chunk):
                tokens, skip = line.split(), False
                for tok in tokens:
                    if skip:
                        skip = False
                    elif tok.startswith("-"):
                        skip = tok in VALUED
                    elif re.fullmatch(r"[a-z][a-z_]*", tok):
                        out.append((page, tok))
    return out


def test_every_snakemake_target_the_guide_names_is_a_rule():
    rules = set()
    for smk in [ROOT / "workflow" / "Snakefile", *(ROOT / "workflow" / "rules").glob("*.smk")]:
        rules |= set(re.findall(r"(?m)^rule (\w+):", smk.read_text()))
    named = snakemake_targets(guide_code())
    wrong = [(str(page), t) for page, t in named if t not in rules]
    assert len(named) > 5 and not wrong, wrong


def _in_schema(schema, parts):
    for part in parts:
        props = schema.get("properties", {})
        if part == "*" or part.startswith("<"):
            extra = schema.get("additionalProperties")
            if isinstance(extra, dict):
                schema = extra
                continue
            if props:        # a wildcard over the section's own keys
                return any(_in_schema(s, parts[parts.index(part) + 1:]) for s in props.values())
            return False
        if part not in props:
            return False
        schema = props[part]
    return True


def test_every_config_key_the_guide_names_exists():
    schema = load_schema("config")
    sections = set(schema["properties"])
    named = [(page, span) for page, chunks in guide_code().items() for span in chunks
             if re.fullmatch(r"[a-z_]+(?:\.(?:[A-Za-z0-9_]+|\*|<[a-z]+>))+", span) and span.split(".")[0] in sections
             and span.rsplit(".", 1)[1] not in FILE_SUFFIXES]
    wrong = [(str(page), key) for page, key in named if not _in_schema(schema, key.split("."))]
    assert len(named) > 10 and not wrong, wrong


def test_every_bench_script_is_in_the_benchmarks_page():
    page = (ROOT / "docs" / "reference" / "benchmarks.md").read_text()
    missing = [p.name for p in sorted((ROOT / "bench").iterdir()) if p.is_file() and f"bench/{p.name}" not in page]
    assert not missing, missing


def test_every_rule_has_a_docstring():
    """The targets page and `snakemake --list-rules` read them."""
    for smk in [ROOT / "workflow" / "Snakefile", *(ROOT / "workflow" / "rules").glob("*.smk")]:
        text = smk.read_text()
        bare = re.findall(r'(?m)^rule (\w+):\n(?!\s+""")', text)
        assert not bare, (smk.name, bare)
