# Parametric study (thesis 4.4): F_str_co and mu one at a time, `parametric.cases` box-test
# cases per value on the study's assembled cases -> results/parametric/ (parametric.nc,
# report.md with slopes, sensitivity and the thesis' two findings, one figure per
# parameter). `snakemake --cores 2 parametric`; not part of `all`.
PARAMETRIC = config["parametric"]
PARAM_DB = PARAMETRIC["database"]
PARAM_SETTINGS = [(name, f"{v:g}") for name in ("F_str_co", "mu") for v in PARAMETRIC[name]]
PARAM_CYCLES = RigParams.from_config(config.get("rig")).cycles


rule parametric_setting:
    output:
        f"{RESULTS}/parametric/settings/{{name}}_{{value}}.yaml",
    log:
        f"{RESULTS}/logs/parametric/{{name}}_{{value}}_setting.log",
    shell:
        "ballaststudy parametric setting {wildcards.name} {wildcards.value} --out {output} > {log} 2>&1"


rule parametric_run:
    input:
        assembled=f"{RESULTS}/cases/{PARAM_DB}/case{{case}}/assembled.nc",
        parameters=f"{RESULTS}/parametric/settings/{{name}}_{{value}}.yaml",
    output:
        f"{RESULTS}/parametric/{{name}}_{{value}}/case{{case}}/metrics.nc",
    params:
        loading=box_stage("loading"),
        cycles=PARAM_CYCLES,
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/parametric/{{name}}_{{value}}_case{{case}}.log",
    shell:
        "ballaststudy case run {input.assembled} --cycles {params.cycles} --parameters "
        "{input.parameters} --config {params.config} --out {output} --no-vtk --no-figures "
        "--quiet > {log} 2>&1"


rule parametric:
    input:
        [f"{RESULTS}/parametric/{name}_{value}/case{case}/metrics.nc"
         for name, value in PARAM_SETTINGS for case in range(PARAMETRIC["cases"])],
    output:
        nc=f"{RESULTS}/parametric/parametric.nc",
        md=report(f"{RESULTS}/parametric/report.md", caption="../report/parametric.rst", category="Parametric"),
        figures=report([f"{RESULTS}/parametric/{name}.png" for name in ("F_str_co", "mu")],
                       caption="../report/parametric.rst", category="Parametric"),
    log:
        f"{RESULTS}/logs/parametric/report.log",
    shell:
        "ballaststudy parametric report {input} --out-dir {RESULTS}/parametric --quiet > {log} 2>&1"
