# Stage 2: bonded particle models of the 2D forms (thesis 4.2.1), one library per database.

rule bpm_build:
    """One form database's stones as bonded-particle stones (balls glued by flat joints): results/bpm/<database>.nc."""
    input:
        f"{RESULTS}/forms/{{db}}.nc",
    output:
        f"{RESULTS}/bpm/{{db}}.nc",
    params:
        # the bpm settings and the study seed: editing them reruns every library
        bpm=trigger("bpm"),
        seed=config["seed"],
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/bpm/{{db}}.log",
    shell:
        "ballaststudy bpm build {input} --out {output} --config {params.config} --quiet > {log} 2>&1"


rule bpm_all:
    """Every selected database's bonded-particle stones."""
    input:
        expand(f"{RESULTS}/bpm/{{db}}.nc", db=NAMES),
