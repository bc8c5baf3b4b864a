# Stage 3: box-test cases (thesis 4.2.2, 4.2.3): one assembly and one loading run per
# (database, case). Inputs: the bpm stage's library results/bpm/{db}.nc.
# Config: rig.box.assembly and rig.box.loading (each stage reruns when its section is
# edited); cases per database: study.cases_per_database (default 10, as in the thesis);
# material parameters: study.parameters (table_4_2, or calibrated: the calibrate target's
# calibrated.yaml, so the study follows the calibration).
from ballaststudy.rig.params import RigParams

CASES = list(range(int(config.get("study", {}).get("cases_per_database", 10))))


rule case_assemble:
    """One box-test case assembled: stones dropped, tamped and relaxed in the container (thesis 4.2.2)."""
    input:
        bpm=f"{RESULTS}/bpm/{{db}}.nc",
    output:
        f"{RESULTS}/cases/{{db}}/case{{case}}/assembled.nc",
    params:
        assembly=box_assembly_trigger(),   # editing the assembly section (or the plate's moves): reassemble
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/cases/{{db}}/case{{case}}_assemble.log",
    shell:
        "ballaststudy case assemble {input.bpm} --case {wildcards.case} --config {params.config} "
        "--out {output} --quiet > {log} 2>&1"


CALIBRATED = config["study"]["parameters"] == "calibrated"   # else Table 4.2's


rule case_run:
    """One box-test case loaded: static pre-loads, then rig.box.loading.cycles load cycles; its per-cycle metrics.nc (thesis 4.2.3, 4.5)."""
    input:
        assembled=f"{RESULTS}/cases/{{db}}/case{{case}}/assembled.nc",
        parameters=[f"{CAL_OUT}/calibrated.yaml"] if CALIBRATED else [],
    output:
        metrics=f"{RESULTS}/cases/{{db}}/case{{case}}/metrics.nc",
        case_png=f"{RESULTS}/cases/{{db}}/case{{case}}/case.png",
        curves=f"{RESULTS}/cases/{{db}}/case{{case}}/behaviours.png",
    params:
        loading=trigger("rig.box.loading"),   # editing the loading or metrics section: rerun the loading
        metrics=trigger("metrics"),
        stones=stones_trigger(),   # the stone model, its splitting: rerun the loading
        cycles=RigParams.from_config(config.get("rig")).cycles,
        parameters=f"--parameters {CAL_OUT}/calibrated.yaml" if CALIBRATED else "",
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/cases/{{db}}/case{{case}}_run.log",
    shell:
        # a rerun after an interruption resumes from metrics.checkpoint.npz beside the output
        "ballaststudy case run {input.assembled} --cycles {params.cycles} {params.parameters} "
        "--config {params.config} --out {output.metrics} --quiet > {log} 2>&1"


rule cases_all:
    """Every box-test case of every selected database, assembled and loaded."""
    input:
        expand(f"{RESULTS}/cases/{{db}}/case{{case}}/metrics.nc", db=NAMES, case=CASES),
