# The monotonic strength test (config section ``strength``): the first `cases` specimens of
# a biaxial set compressed through their peak at every confining pressure of the measured
# tests the biaxial rig runs -> results/strength/<set>/p<p>kPa/case<k>.nc, and their
# envelope results/strength/<set>/envelope.nc: `snakemake --cores 2 strength` for the set
# strength.specimens; a stage under stress_mapping strength_ratio asks for its own set's.
from ballaststudy.rig.kinds import kind_for_test

STRENGTH = config["strength"]
STRENGTH_P = sorted({load_conditions(MEASURED_TESTS_DIR / f"{t}.yaml")["confining_pressure_kPa"]
                     for t in MEASURED_TESTS
                     if kind_for_test(load_conditions(MEASURED_TESTS_DIR / f"{t}.yaml")["rig"]) == "biaxial"})
STRENGTH_DIR = f"{RESULTS}/strength/{STRENGTH['specimens']}"


rule strength_case:
    """One monotonic strength test of a biaxial specimen at confining pressure p, through the peak."""
    input:
        specimen=f"{RESULTS}/specimens/{{set}}/case{{case}}.nc",
    output:
        f"{RESULTS}/strength/{{set}}/p{{p}}kPa/case{{case}}.nc",
    params:
        strength=trigger("strength", drop=("specimens", "cases")),
        # the keys the test sets itself (p from the wildcard) rerun nothing
        loading=trigger("rig.biaxial.loading", drop=("confining_pressure_kPa", "mode", "failure_axial_strain",
                                                     "max_cycle_steps")),
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/strength/{{set}}/p{{p}}kPa/case{{case}}.log",
    shell:
        "ballaststudy case strength {input.specimen} --confining-pressure-kPa {wildcards.p} "
        "--case {wildcards.case} --config {params.config} --out {output} --quiet > {log} 2>&1"


rule strength_envelope:
    """A specimen set's strength envelope (q_peak, phi_peak, dilatancy per p) from its strength tests."""
    input:
        lambda wc: expand(f"{RESULTS}/strength/{wc.set}/p{{p}}kPa/case{{case}}.nc",
                          p=[f"{p:g}" for p in STRENGTH_P], case=range(STRENGTH["cases"])),
    output:
        f"{RESULTS}/strength/{{set}}/envelope.nc",
    log:
        f"{RESULTS}/logs/strength/{{set}}/envelope.log",
    shell:
        "ballaststudy case envelope {input} --out {output} --quiet > {log} 2>&1"


rule strength:
    """The strength envelope of strength.specimens at every p of the measured tests."""
    input:
        f"{STRENGTH_DIR}/envelope.nc",
