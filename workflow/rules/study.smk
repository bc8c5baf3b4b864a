# Stage 4: the study (thesis ch. 5): per-case metrics -> study.nc -> IRI tables and the
# optimisation report with the thesis' findings checked.
from ballaststudy.study.plots import figure_names


rule study_aggregate:
    """Every case's per-cycle metrics with the form databases' properties in one results/study.nc (database x case x cycle)."""
    input:
        metrics=expand(f"{RESULTS}/cases/{{db}}/case{{case}}/metrics.nc", db=NAMES, case=CASES),
        forms=expand(f"{RESULTS}/forms/{{db}}.nc", db=NAMES),
    output:
        report(f"{RESULTS}/study.nc", caption="../report/study.rst", category="Study"),
    log:
        f"{RESULTS}/logs/study/aggregate.log",
    shell:
        "ballaststudy study aggregate {input.metrics} --forms {input.forms} --out {output} > {log} 2>&1"


rule study_iri:
    """The IRI tables of the study (thesis Table 5-2): each form parameter's relation to each behaviour, with bootstrap intervals."""
    input:
        f"{RESULTS}/study.nc",
    output:
        csv=f"{RESULTS}/study/iri/iri.csv",
        thesis=f"{RESULTS}/study/iri/iri_thesis.csv",
        md=f"{RESULTS}/study/iri/iri.md",
        heatmap=report(f"{RESULTS}/study/iri/iri_heatmap.png", caption="../report/iri.rst", category="Study"),
    params:
        out_dir=f"{RESULTS}/study/iri",
        resamples=config["study"]["bootstrap_resamples"],
        seed=config["study"]["bootstrap_seed"],
    log:
        f"{RESULTS}/logs/study/iri.log",
    shell:
        "ballaststudy study iri {input} --out {params.out_dir} --resamples {params.resamples} "
        "--seed {params.seed} > {log} 2>&1"


rule study_optimise:
    """The study's ranking, Pareto set, the thesis' findings checked and the optimised gradation (thesis ch. 5)."""
    input:
        f"{RESULTS}/study.nc",
    output:
        md=report(f"{RESULTS}/study/report/report.md", caption="../report/optimise.rst", category="Study"),
        ranking=f"{RESULTS}/study/report/ranking.csv",
        findings=f"{RESULTS}/study/report/findings.csv",
        figures=report([f"{RESULTS}/study/report/{name}" for name in figure_names()],
                       caption="../report/figures.rst", category="Study"),
    params:
        out_dir=f"{RESULTS}/study/report",
        resamples=config["study"]["bootstrap_resamples"],
        seed=config["study"]["bootstrap_seed"],
    log:
        f"{RESULTS}/logs/study/optimise.log",
    shell:
        "ballaststudy study optimise {input} --out {params.out_dir} --resamples {params.resamples} "
        "--seed {params.seed} > {log} 2>&1"
