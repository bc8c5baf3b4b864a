# Parametric study (thesis 4.4): F_str_co and mu one at a time, `parametric.cases` box-test
# cases per value on the study's assembled cases, and `parametric.design_sets` sets of both
# at once (a Latin hypercube over the same ranges) for the Sobol indices -> results/parametric/
# (parametric.nc, report.md with slopes, sensitivity and the thesis' two findings, one
# figure per parameter). `snakemake --cores 2 parametric`; not part of `all`.
from ballaststudy.calibration.parametric import design_sets
from ballaststudy.config import job_seed

PARAMETRIC = config["parametric"]
PARAM_SPECIMENS = specimen_files("parametric")
PARAM_CYCLES = RigParams.from_config(config.get("rig")).cycles
# setting name -> {parameter: value}: one at a time, then the design (seeded by the config)
PARAM_SETTINGS = {f"{name}_{v:g}": {name: v} for name in ("F_str_co", "mu") for v in PARAMETRIC[name]}
PARAM_SETTINGS.update({f"design{j}": values for j, values in enumerate(design_sets(
    {k: (min(PARAMETRIC[k]), max(PARAMETRIC[k])) for k in ("F_str_co", "mu")},
    PARAMETRIC["design_sets"], job_seed(config["seed"], "parametric/design")))})


wildcard_constraints:
    setting="[^/]+",


rule parametric_setting:
    """One parameter setting of the parametric study as a calibrated.yaml."""
    output:
        f"{RESULTS}/parametric/settings/{{setting}}.yaml",
    params:
        pairs=lambda wc: " ".join(f"{k} {v!r}" for k, v in PARAM_SETTINGS[wc.setting].items()),
    log:
        f"{RESULTS}/logs/parametric/{{setting}}_setting.log",
    shell:
        "ballaststudy parametric setting {params.pairs} --out {output} > {log} 2>&1"


rule parametric_run:
    """One box-test case loaded under one parametric setting."""
    input:
        assembled=lambda wc: PARAM_SPECIMENS[int(wc.case)],
        parameters=f"{RESULTS}/parametric/settings/{{setting}}.yaml",
    output:
        f"{RESULTS}/parametric/{{setting}}/case{{case}}/metrics.nc",
    params:
        loading=trigger("rig.box.loading"),
        metrics=trigger("metrics"),
        stones=stones_trigger(),   # the stone model, its splitting: rerun the loading
        cycles=PARAM_CYCLES,
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/parametric/{{setting}}_case{{case}}.log",
    shell:
        "ballaststudy case run {input.assembled} --cycles {params.cycles} --parameters "
        "{input.parameters} --config {params.config} --out {output} --no-vtk --no-figures "
        "--quiet > {log} 2>&1"


rule parametric:
    """The parametric study (thesis 4.4): settlement and breakage against F_str_co and mu, slopes and Sobol indices: results/parametric/."""
    input:
        [f"{RESULTS}/parametric/{setting}/case{case}/metrics.nc"
         for setting in PARAM_SETTINGS for case in range(PARAMETRIC["cases"])],
    output:
        nc=f"{RESULTS}/parametric/parametric.nc",
        md=report(f"{RESULTS}/parametric/report.md", caption="../report/parametric.rst", category="Parametric"),
        figures=report([f"{RESULTS}/parametric/{name}.png" for name in ("F_str_co", "mu")],
                       caption="../report/parametric.rst", category="Parametric"),
    params:
        out_dir=f"{RESULTS}/parametric",
    log:
        f"{RESULTS}/logs/parametric/report.log",
    shell:
        "ballaststudy parametric report {input} --out-dir {params.out_dir} --quiet > {log} 2>&1"
