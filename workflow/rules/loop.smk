# Closing the loop with measured data (issue 14): the plain model and every candidate effect
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


rule loop_assemble:
    input:
        bpm=f"{RESULTS}/bpm/{LOOP['database']}.nc",
    output:
        f"{RESULTS}/loop/specimens/{LOOP['database']}/case{{case}}.nc",
    params:
        assembly=json.dumps((config["rig"].get("biaxial") or {}).get("assembly") or {}, sort_keys=True),
        size=" ".join(f"--{k.replace('_', '-')} {LOOP[k]}" for k in ("width_m", "height_m")
                      if LOOP.get(k) is not None),
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/loop/specimen{{case}}.log",
    shell:
        "ballaststudy case assemble {input.bpm} --case {wildcards.case} --rig biaxial "
        "{params.size} --config {params.config} --out {output} --quiet > {log} 2>&1"


rule loop:
    input:
        measured=[f"{RESULTS}/measured/{t}.nc" for t in LOOP["targets"]],
        conditions=[str(MEASURED_TESTS_DIR / f"{t}.yaml") for t in LOOP["targets"]],
        specimens=expand(f"{RESULTS}/loop/specimens/{LOOP['database']}/case{{case}}.nc",
                         case=range(LOOP["cases"])),
        parameters=[f"{CAL_OUT}/calibrated.yaml"] if LOOP_CALIBRATED else [],
    output:
        md=report(f"{RESULTS}/loop/report.md", caption="../report/loop.rst", category="Loop"),
        nc=f"{RESULTS}/loop/loop.nc",
        chosen=f"{RESULTS}/loop/chosen.yaml",
        png=report(f"{RESULTS}/loop/curves.png", caption="../report/loop.rst", category="Loop"),
    params:
        loop=json.dumps(LOOP, sort_keys=True),
        rig=json.dumps((config["rig"].get("biaxial") or {}).get("loading") or {}, sort_keys=True),
        parameters=f"--parameters {CAL_OUT}/calibrated.yaml" if LOOP_CALIBRATED else "",
        config=CONFIG_FILE,
    threads: 256      # Snakemake caps it at --cores
    log:
        f"{RESULTS}/logs/loop/loop.log",
    shell:
        "ballaststudy loop {input.measured} --conditions {input.conditions} --specimens "
        "{input.specimens} {params.parameters} --out-dir {RESULTS}/loop --jobs {threads} "
        "--config {params.config} --quiet > {log} 2>&1"
