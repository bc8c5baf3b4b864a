# Measured cyclic tests in: every conditions YAML under measured.tests_dir (one test each,
# its curve files beside it or in measured.data_dir) -> results/measured/<test>.nc.
# A user adds a test by dropping its YAML (+ curve files) into the folder. The public curves
# the shipped tests read are fetched into measured.data_dir (measured_fetch) when a target
# needs them; `all` leaves the tests out until they are there, so it runs offline.
import shlex
from pathlib import Path

from ballaststudy.measured.fetch import SOURCE_REPOSITORY, registered_files
from ballaststudy.measured.importer import curve_files, load_conditions

MEASURED_TESTS_DIR = Path(config["measured"]["tests_dir"])
MEASURED_DATA_DIR = Path(config["measured"]["data_dir"])
MEASURED_TESTS = sorted(str(p.relative_to(MEASURED_TESTS_DIR).with_suffix(""))
                        for p in MEASURED_TESTS_DIR.rglob("*.yaml"))
for _test in MEASURED_TESTS:        # one line naming file and key before any job
    try:
        load_conditions(MEASURED_TESTS_DIR / f"{_test}.yaml")
    except ConfigError as err:
        stop(err)
MEASURED_AVAILABLE = all(p.is_file() for t in MEASURED_TESTS
                         for p in curve_files(MEASURED_TESTS_DIR / f"{t}.yaml", MEASURED_DATA_DIR))
if not MEASURED_AVAILABLE:
    print(f"note: the measured curves are not in measured.data_dir {MEASURED_DATA_DIR}: "
          f"`snakemake --cores 1 measured_fetch` fetches them from {SOURCE_REPOSITORY} "
          f"(a target that reads them does too); until then 'all' leaves out the {len(MEASURED_TESTS)} "
          "measured tests", file=sys.stderr)


rule measured_fetch_files:
    """The public measured curves downloaded into measured.data_dir, each checked by its SHA-256."""
    output:
        [str(MEASURED_DATA_DIR / name) for name in registered_files()],
    params:
        data_dir=MEASURED_DATA_DIR,
        url="" if config["measured"]["source_url"] is None else f"--url {shlex.quote(config['measured']['source_url'])}",
    log:
        f"{RESULTS}/logs/measured/fetch.log",
    shell:
        "ballaststudy measured fetch --data-dir {params.data_dir} {params.url} --quiet > {log} 2>&1"


rule measured_fetch:
    """Fetch the public measured curves (the target a user names; a target that reads them fetches them too)."""
    input:
        rules.measured_fetch_files.output,


def measured_inputs(wildcards):
    conditions = MEASURED_TESTS_DIR / f"{wildcards.test}.yaml"
    return [str(conditions)] + [str(p) for p in curve_files(conditions, MEASURED_DATA_DIR)]


rule measured_import:
    """One measured test (its conditions YAML and curve files) to results/measured/<test>.nc."""
    input:
        measured_inputs,
    output:
        f"{RESULTS}/measured/{{test}}.nc",
    params:
        conditions=lambda wc: MEASURED_TESTS_DIR / f"{wc.test}.yaml",
        data_dir=MEASURED_DATA_DIR,
    log:
        f"{RESULTS}/logs/measured/{{test}}.log",
    shell:
        "ballaststudy measured import {params.conditions} --data-dir {params.data_dir} "
        "--out {output} --quiet > {log} 2>&1"


rule measured_all:
    """Every measured test under measured.tests_dir imported."""
    input:
        expand(f"{RESULTS}/measured/{{test}}.nc", test=MEASURED_TESTS),


# Every measured test simulated: the first `cases` specimens of the set measured.sim.specimens
# (shared by all tests: the conditions only act on the loading), each run under the test's
# p, q and f.
MEASURED_SIM = config["measured"]["sim"]
SIM_SPECIMENS = specimen_files("measured.sim")
SIM_CASES = list(range(MEASURED_SIM["cases"]))


rule measured_sim_run:
    """One measured test simulated on one specimen of measured.sim.specimens under the test's p, q and f."""
    input:
        specimen=lambda wc: SIM_SPECIMENS[int(wc.case)],
        conditions=lambda wc: MEASURED_TESTS_DIR / f"{wc.test}.yaml",
        envelope=mapping_input("measured.sim"),
    output:
        f"{RESULTS}/measured_sim/cases/{{test}}/case{{case}}.nc",
    params:
        loading=lambda wc: trigger("rig.biaxial.loading", drop=conditioned_keys("biaxial", [wc.test])),
        metrics=trigger("metrics"),
        stones=stones_trigger(),   # the stone model, its splitting: rerun the loading
        cycles=MEASURED_SIM["cycles"],
        mode=MEASURED_SIM["mode"],
        mapping=mapping_option("measured.sim"),
        mapping_settings=trigger("stress_mapping"),
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/measured_sim/{{test}}/case{{case}}.log",
    shell:
        "ballaststudy case run {input.specimen} --cycles {params.cycles} --conditions "
        "{input.conditions} --mode {params.mode} {params.mapping} --config {params.config} --out {output} "
        "--no-vtk --no-figures --quiet > {log} 2>&1"


rule measured_sim_compare:
    """One measured test beside its simulated cases, on one cycle axis: a netCDF and a figure."""
    input:
        measured=f"{RESULTS}/measured/{{test}}.nc",
        cases=lambda wc: expand(f"{RESULTS}/measured_sim/cases/{wc.test}/case{{case}}.nc",
                                case=SIM_CASES),
    output:
        nc=f"{RESULTS}/measured_sim/compare/{{test}}.nc",
        png=f"{RESULTS}/measured_sim/compare/{{test}}.png",
    log:
        f"{RESULTS}/logs/measured_sim/{{test}}/compare.log",
    shell:
        "ballaststudy measured compare {input.measured} {input.cases} --out {output.nc} "
        "--quiet > {log} 2>&1"


rule measured_sim:
    """Every measured test simulated and compared with its measured curves."""
    input:
        expand(f"{RESULTS}/measured_sim/compare/{{test}}.nc", test=MEASURED_TESTS),
