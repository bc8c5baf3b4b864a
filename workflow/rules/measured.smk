# Measured cyclic tests in: every conditions YAML under measured.tests_dir (one test each,
# its curve files beside it or in measured.data_dir) -> results/measured/<test>.nc.
# A user adds a test by dropping its YAML (+ curve files) into the folder.
import os
from pathlib import Path

from ballaststudy.measured.importer import curve_files, load_conditions

MEASURED_TESTS_DIR = Path(config["measured"]["tests_dir"])
MEASURED_DATA_DIR = Path(config["measured"]["data_dir"])
MEASURED_TESTS = sorted(str(p.relative_to(MEASURED_TESTS_DIR).with_suffix(""))
                        for p in MEASURED_TESTS_DIR.rglob("*.yaml"))
for _test in MEASURED_TESTS:        # one line naming file and key before any job
    load_conditions(MEASURED_TESTS_DIR / f"{_test}.yaml")
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
