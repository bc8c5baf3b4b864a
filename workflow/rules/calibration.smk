# Calibration (thesis 4.3): the config's parameters fitted to one or more measured tests
# with the rig that runs them (triaxial tests: biaxial; box tests: box)
# -> results/calibration/<target, or calibration.name>/ (calibrated.yaml, evaluations.nc, posterior.nc,
# figures, summary.md). `snakemake --cores 2 calibrate`; not part of `all`. The cases of
# every parameter set are cached under cases/<hash>/: an interrupted run resumes.
from ballaststudy.calibration.cli import check_targets, targets_kind

CALIBRATION = config["calibration"]
CAL_TARGETS = CALIBRATION["targets"]
try:                                      # before any job: one line, file and key
    CAL_OUT = f"{RESULTS}/calibration/{check_targets(config, CONFIG_FILE, MEASURED_TESTS)}"
    CAL_KIND = targets_kind(config, CONFIG_FILE, MEASURED_TESTS_DIR) if MEASURED_TESTS else "biaxial"
except ConfigError as err:
    stop(err)


rule calibrate:
    """The calibration's parameters fitted to the measured tests calibration.targets (Gaussian-process surrogate, multivariate t likelihood, sequential design): results/calibration/<name>/."""
    input:
        measured=[f"{RESULTS}/measured/{t}.nc" for t in CAL_TARGETS],
        conditions=[str(MEASURED_TESTS_DIR / f"{t}.yaml") for t in CAL_TARGETS],
        specimens=specimen_files("calibration"),
        envelope=mapping_input("calibration"),
    output:
        yaml=f"{CAL_OUT}/calibrated.yaml",
        nc=f"{CAL_OUT}/evaluations.nc",
        posterior=f"{CAL_OUT}/posterior.nc",
        summary=report(f"{CAL_OUT}/summary.md", caption="../report/calibration.rst", category="Calibration"),
        figures=report([f"{CAL_OUT}/curves.png", f"{CAL_OUT}/corner.png"],
                       caption="../report/calibration.rst", category="Calibration"),
    params:
        calibration=trigger("calibration"),
        rig=trigger(f"rig.{CAL_KIND}.loading", drop=conditioned_keys(CAL_KIND, CAL_TARGETS)),
        metrics=trigger("metrics"),
        stones=stones_trigger(),   # the stone model, its splitting: rerun the loading
        out_dir=CAL_OUT,
        config=CONFIG_FILE,
        backend=config["backend"],
        mapping=mapping_option("calibration"),
        mapping_settings=trigger("stress_mapping"),
    # its cases in --jobs processes here; a light coordinator where they run in the
    # executor's workers (config executor; the SLURM profile gives it a long runtime)
    threads: 256 if EXECUTOR.kind == "local" else 1      # Snakemake caps it at --cores
    log:
        f"{RESULTS}/logs/calibration/calibrate.log",
    shell:
        "ballaststudy calibrate {input.measured} --conditions {input.conditions} "
        "--specimens {input.specimens} --out-dir {params.out_dir} --jobs {threads} "
        "--backend {params.backend} {params.mapping} --config {params.config} --quiet > {log} 2>&1"
