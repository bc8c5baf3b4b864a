# ballaststudy: the whole chain on one command (`snakemake --cores 2`).
# Thin rules: every rule calls one `ballaststudy` subcommand; the logic is in the package.
# Config: config/config.yaml (or --configfile), validated by workflow/schemas/ at start.
from snakemake.utils import min_version, validate

from ballaststudy.config import database_seed, form_params, load_databases, select_databases

min_version("8.0")


configfile: "config/config.yaml"


validate(config, "workflow/schemas/config.schema.yaml")
CONFIG_FILE = (workflow.overwrite_configfiles or ["config/config.yaml"])[-1]
DATABASES = load_databases(config["databases_file"], form_params(config))
NAMES = select_databases(config, DATABASES, CONFIG_FILE)
RESULTS = config["results_dir"]


include: "workflow/rules/forms.smk"
include: "workflow/rules/bpm.smk"
include: "workflow/rules/cases.smk"
include: "workflow/rules/study.smk"


rule all:
    input:
        rules.forms_report.output,
        rules.study_iri.output,
        rules.study_optimise.output,
