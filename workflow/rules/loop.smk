# Closing the loop with measured data: the plain model and every candidate effect
# (loop.effects) run under each target test, effects judged on held-out tests ->
# results/loop/ (report.md, loop.nc, chosen.yaml, curves.png). `snakemake --cores 2 loop`;
# not part of `all`. Cases are cached by parameter hash under cases/: an interrupted loop resumes.
from ballaststudy.loop.cli import check_loop_targets

LOOP = config["loop"]
try:                                      # before any job: one line, file and key
    check_loop_targets(config, CONFIG_FILE, MEASURED_TESTS, MEASURED_TESTS_DIR)
except ConfigError as err:
    stop(err)
LOOP_CALIBRATED = LOOP["parameters"] == "calibrated"
# every measured cyclic triaxial/biaxial test judges the long-term laws, not only the targets
HORIZON_TESTS = [t for t in MEASURED_TESTS if load_conditions(MEASURED_TESTS_DIR / f"{t}.yaml")["rig"] != "box"]


# `snakemake --cores 2 horizon`: each accumulation law fitted to every measured
# curve up to loop.horizon_fit_cycles and read at its last point -> results/horizon/
# (horizon.md, horizon.nc, horizon.png); the loop extrapolates with the law chosen there.
rule horizon:
    """Each accumulation law fitted to every measured curve up to loop.horizon_fit_cycles and read at its last point; the law the loop extrapolates with: results/horizon/."""
    input:
        [f"{RESULTS}/measured/{t}.nc" for t in HORIZON_TESTS],
    output:
        md=report(f"{RESULTS}/horizon/horizon.md", caption="../report/loop.rst", category="Loop"),
        nc=f"{RESULTS}/horizon/horizon.nc",
        png=report(f"{RESULTS}/horizon/horizon.png", caption="../report/loop.rst", category="Loop"),
    params:
        out_dir=f"{RESULTS}/horizon",
        fit_cycles=" ".join(f"{n:g}" for n in LOOP["horizon_fit_cycles"]),
        quantity=LOOP["quantity"],
    log:
        f"{RESULTS}/logs/loop/horizon.log",
    shell:
        "ballaststudy horizon {input} --out-dir {params.out_dir} --fit-cycles {params.fit_cycles} "
        "--quantity {params.quantity} --quiet > {log} 2>&1"


rule loop:
    """The model against the measured tests loop.targets: the plain model and every candidate effect, each judged on tests left out, with the discrepancy per source and the verdict: results/loop/."""
    input:
        measured=[f"{RESULTS}/measured/{t}.nc" for t in LOOP["targets"]],
        conditions=[str(MEASURED_TESTS_DIR / f"{t}.yaml") for t in LOOP["targets"]],
        specimens=specimen_files("loop"),
        parameters=[f"{CAL_OUT}/calibrated.yaml"] if LOOP_CALIBRATED else [],
        horizon=f"{RESULTS}/horizon/horizon.nc",
        envelope=mapping_input("loop"),
    output:
        md=report(f"{RESULTS}/loop/report.md", caption="../report/loop.rst", category="Loop"),
        nc=f"{RESULTS}/loop/loop.nc",
        chosen=f"{RESULTS}/loop/chosen.yaml",
        png=report(f"{RESULTS}/loop/curves.png", caption="../report/loop.rst", category="Loop"),
    params:
        out_dir=f"{RESULTS}/loop",
        loop=trigger("loop"),
        rig=trigger("rig.biaxial.loading", drop=conditioned_keys("biaxial", LOOP["targets"])),
        metrics=trigger("metrics"),
        stones=stones_trigger(),   # the stone model, its splitting: rerun the loading
        parameters=f"--parameters {CAL_OUT}/calibrated.yaml" if LOOP_CALIBRATED else "",
        config=CONFIG_FILE,
        backend=config["backend"],
        mapping=mapping_option("loop"),
        mapping_settings=trigger("stress_mapping"),
    # its cases in --jobs processes here; a light coordinator where they run in the
    # executor's workers (config executor; the SLURM profile gives it a long runtime)
    threads: 256 if EXECUTOR.kind == "local" else 1      # Snakemake caps it at --cores
    log:
        f"{RESULTS}/logs/loop/loop.log",
    shell:
        "ballaststudy loop {input.measured} --conditions {input.conditions} --specimens "
        "{input.specimens} {params.parameters} --horizon {input.horizon} --out-dir {params.out_dir} --jobs {threads} "
        "--backend {params.backend} {params.mapping} --config {params.config} --quiet > {log} 2>&1"
