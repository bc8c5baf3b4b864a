# ballaststudy: the whole chain on one command (`snakemake --cores 2`).
# Thin rules: every rule calls one `ballaststudy` subcommand; the logic is in the package.
# Config: config/config.yaml (or --configfile), validated by workflow/schemas/ at start.
import sys

from snakemake.utils import min_version, validate

from ballaststudy.config import check_domain, database_seed, validate as validate_file, form_params, load_databases, select_databases

min_version("8.0")


configfile: "config/config.yaml"


CONFIG_FILE = (workflow.overwrite_configfiles or ["config/config.yaml"])[-1]
# our one-line message (file, key, allowed range) first, then Snakemake's own validation
# against the same schema (it also fills the defaults)
check_domain(validate_file(config, "config", CONFIG_FILE), CONFIG_FILE)
validate(config, "workflow/schemas/config.schema.yaml")
DATABASES = load_databases(config["databases_file"], form_params(config))
NAMES = select_databases(config, DATABASES, CONFIG_FILE)
RESULTS = config["results_dir"]


include: "workflow/rules/forms.smk"
include: "workflow/rules/bpm.smk"
include: "workflow/rules/cases.smk"
include: "workflow/rules/study.smk"
include: "workflow/rules/measured.smk"


rule all:
    input:
        rules.forms_report.output,
        rules.study_iri.output,
        rules.study_optimise.output,
        rules.measured_all.input if MEASURED_AVAILABLE else [],
