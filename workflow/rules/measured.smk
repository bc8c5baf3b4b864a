# Measured cyclic tests in: every conditions YAML under measured.tests_dir (one test each,
# its curve files beside it or in measured.data_dir) -> results/measured/<test>.nc.
# A user adds a test by dropping its YAML (+ curve files) into the folder.
from pathlib import Path

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
MEASURED_AVAILABLE = MEASURED_DATA_DIR.is_dir() or not MEASURED_TESTS
if not MEASURED_AVAILABLE:
    print(f"note: measured.data_dir {MEASURED_DATA_DIR} not found: the {len(MEASURED_TESTS)} "
          "measured tests are left out of 'all'", file=sys.stderr)


def measured_inputs(wildcards):
    conditions = MEASURED_TESTS_DIR / f"{wildcards.test}.yaml"
    return [str(conditions)] + [str(p) for p in curve_files(conditions, MEASURED_DATA_DIR)]


rule measured_import:
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
    input:
        expand(f"{RESULTS}/measured/{{test}}.nc", test=MEASURED_TESTS),


# Every measured test simulated: the first `cases` specimens of the set measured.sim.specimens
# (shared by all tests: the conditions only act on the loading), each run under the test's
# p, q and f.
MEASURED_SIM = config["measured"]["sim"]
SIM_SPECIMENS = specimen_files("measured.sim")
SIM_CASES = list(range(MEASURED_SIM["cases"]))


rule measured_sim_run:
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
    input:
        expand(f"{RESULTS}/measured_sim/compare/{{test}}.nc", test=MEASURED_TESTS),
