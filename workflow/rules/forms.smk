# Stage 1: the ballast random form generator (thesis ch. 3), one job per database.

rule forms_generate:
    """One form database: random EN 13450 stones to its grading and shape indices, with their STL files."""
    output:
        nc=f"{RESULTS}/forms/{{db}}.nc",
        stl=f"{RESULTS}/forms/{{db}}.stl.zip",
    params:
        out_dir=f"{RESULTS}/forms",
        # the database's own definition and the form settings: editing them reruns this job
        definition=lambda w: json.dumps(DATABASES[w.db], sort_keys=True),  # a database, not a section
        forms=trigger("forms"),
        seed=lambda w: database_seed(config["seed"], w.db, DATABASES[w.db]),
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/forms/{{db}}.log",
    shell:
        "ballaststudy forms generate {wildcards.db} --config {params.config} "
        "--out {params.out_dir} --quiet > {log} 2>&1"


rule forms_report:
    """The form databases' validation table (objective against generated grading and indices) and figures like thesis Figs. 3-9 to 3-16."""
    input:
        expand(f"{RESULTS}/forms/{{db}}.nc", db=NAMES),
    output:
        csv=f"{RESULTS}/forms/report/validation.csv",
        figures=[report(f"{RESULTS}/forms/report/{f}", caption="../report/forms.rst", category="Forms")
                 for f in ("fig_3-9_stones.png", "fig_3-13_particle_numbers.png", "fig_3-14_mass.png",
                           "fig_3-15_shape_index.png", "fig_3-16_particle_length.png")],
    params:
        out_dir=f"{RESULTS}/forms/report",
        stones=config["forms"]["report_stones"],
    log:
        f"{RESULTS}/logs/forms/report.log",
    shell:
        "ballaststudy forms report {input} --out {params.out_dir} --stones {params.stones} > {log} 2>&1"
