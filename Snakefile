# ballaststudy: the whole chain on one command (`snakemake --cores 2`).
# Thin rules: every rule calls one `ballaststudy` subcommand; the logic is in the package.
# Config: config/config.yaml (or --configfile), validated by workflow/schemas/ at start.
import sys
import time

from snakemake.utils import min_version, validate

from ballaststudy.cluster.spec import executor_spec
from ballaststudy.scenario.scenario import check_stone_model

from ballaststudy.config import ConfigError, check_domain, database_seed, validate as validate_file, form_params, load_databases, load_yaml, select_databases, unknown_set_databases

min_version("8.0")


def stop(err):
    """Bad input: our one line (file, key, allowed range), exit 2, no traceback."""
    print(f"ballaststudy: error: {err}", file=sys.stderr)
    sys.exit(2)


# A --configfile is read by Snakemake's command line before this file runs (ConfigSettings
# -> load_configfile), so one it cannot open (a folder, a missing or binary file) is its
# traceback, out of reach here. What it did read is read again here, for what it lets pass
# (a key given twice: the last copy wins); the default config is read here first.
CONFIG_FILES = workflow.overwrite_configfiles or ["config/config.yaml"]
CONFIG_FILE = CONFIG_FILES[-1]
try:  # missing, binary, not YAML, a key twice: our line before Snakemake's traceback
    for path in CONFIG_FILES:
        load_yaml(path)
except ConfigError as err:
    stop(err)


configfile: "config/config.yaml"


# our one-line message first, then Snakemake's own validation against the same schema
try:
    check_domain(validate_file(config, "config", CONFIG_FILE), CONFIG_FILE)
    check_stone_model(config, CONFIG_FILE)
    # where the calibration's and the loop's cases run (the stage checks its batch system)
    EXECUTOR = executor_spec(config, CONFIG_FILE, submit=False)
    DATABASES = load_databases(config["databases_file"], form_params(config))
    NAMES = select_databases(config, DATABASES, CONFIG_FILE)
    for note in unknown_set_databases(config, DATABASES):
        print(note, file=sys.stderr)
except ConfigError as err:
    stop(err)
validate(config, "workflow/schemas/config.schema.yaml")
STARTED = time.time()


onerror:
    # a job's one-line reason, from its log, on the terminal as from the command line
    from ballaststudy.joblogs import error_lines
    for line in error_lines(f"{RESULTS}/logs", STARTED - 1):
        print(line, file=sys.stderr)
RESULTS = config["results_dir"]


include: "workflow/rules/common.smk"
include: "workflow/rules/forms.smk"
include: "workflow/rules/bpm.smk"
include: "workflow/rules/specimens.smk"
include: "workflow/rules/measured.smk"
include: "workflow/rules/strength.smk"
include: "workflow/rules/calibration.smk"
include: "workflow/rules/cases.smk"
include: "workflow/rules/parametric.smk"
include: "workflow/rules/loop.smk"
include: "workflow/rules/study.smk"


rule all:
    """The default job: forms and their report, every box case of every database, the study (IRI, ranking, optimised gradation), and the measured tests' import where their curves are there."""
    input:
        rules.forms_report.output,
        rules.study_iri.output,
        rules.study_optimise.output,
        rules.measured_all.input if MEASURED_AVAILABLE else [],
