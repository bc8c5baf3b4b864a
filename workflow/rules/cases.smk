# Stage 3: box-test cases (thesis 4.2.2, 4.2.3): one assembly and one loading run per
# (database, case). Inputs: the bpm stage's library results/bpm/{db}.nc.
# Config: rig (assembly and loading parameters), rig.cycles; cases per database:
# study.cases_per_database (default 10, as in the thesis).
import json

CASES = list(range(int(config.get("study", {}).get("cases_per_database", 10))))
# rig keys that only the loading stage reads: editing them reruns the case runs, not the assembly
LOADING_KEYS = ("static_", "servo_", "cyclic_", "settlement_force_kN", "cycles", "control_every",
                "loading_dt_factor", "checkpoint_every", "snapshot_every", "timeseries_every",
                "vtk_cycles", "max_cycle_steps")


def rig_params(loading):
    """JSON of the assembly (loading=False) or loading (True) part of config['rig']."""
    rig = config.get("rig", {})
    return json.dumps({k: v for k, v in rig.items() if k.startswith(LOADING_KEYS) == loading}, sort_keys=True)


rule case_assemble:
    input:
        bpm=f"{RESULTS}/bpm/{{db}}.nc",
    output:
        f"{RESULTS}/cases/{{db}}/case{{case}}/assembled.nc",
    params:
        rig=rig_params(loading=False),   # editing an assembly key: reassemble
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/cases/{{db}}/case{{case}}_assemble.log",
    shell:
        "ballaststudy case assemble {input.bpm} --case {wildcards.case} --config {params.config} "
        "--out {output} --quiet > {log} 2>&1"


rule case_run:
    input:
        f"{RESULTS}/cases/{{db}}/case{{case}}/assembled.nc",
    output:
        metrics=f"{RESULTS}/cases/{{db}}/case{{case}}/metrics.nc",
        case_png=f"{RESULTS}/cases/{{db}}/case{{case}}/case.png",
        curves=f"{RESULTS}/cases/{{db}}/case{{case}}/behaviours.png",
    params:
        loading=rig_params(loading=True),   # editing a loading or metrics key: rerun the loading
        metrics=json.dumps(config.get("metrics", {}), sort_keys=True),
        cycles=config.get("rig", {}).get("cycles", 1000),
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/cases/{{db}}/case{{case}}_run.log",
    shell:
        # a rerun after an interruption resumes from metrics.checkpoint.npz beside the output
        "ballaststudy case run {input} --cycles {params.cycles} --config {params.config} "
        "--out {output.metrics} --quiet > {log} 2>&1"


rule cases_all:
    input:
        expand(f"{RESULTS}/cases/{{db}}/case{{case}}/metrics.nc", db=NAMES, case=CASES),
