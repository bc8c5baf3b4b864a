# Specimen sets (config section ``specimens``): every biaxial set assembled once, case by
# case, into results/specimens/<set>/case<k>.nc (each case its own seed from the study seed,
# the database and the case), and used by every stage that names it. A box set needs no
# rule of its own: it is the study's assembled cases (cases.smk).


wildcard_constraints:
    set="[^/]+",


rule specimen_assemble:
    """One biaxial specimen of a specimen set assembled at the set's size: results/specimens/<set>/case<k>.nc (a box set is the study's assembled cases)."""
    input:
        bpm=lambda wc: f"{RESULTS}/bpm/{SPECIMENS[wc.set]['database']}.nc",
    output:
        f"{RESULTS}/specimens/{{set}}/case{{case}}.nc",
    params:
        assembly=trigger("rig.biaxial.assembly"),
        # the set's rig, database and size (not its number of cases: more cases add files)
        definition=lambda wc: json.dumps({k: v for k, v in SPECIMENS[wc.set].items() if k != "cases"},
                                         sort_keys=True),
        size=lambda wc: " ".join(f"--{k.replace('_', '-')} {SPECIMENS[wc.set][k]}" for k in ("width_m", "height_m")
                                 if SPECIMENS[wc.set].get(k) is not None),
        config=CONFIG_FILE,
    log:
        f"{RESULTS}/logs/specimens/{{set}}/case{{case}}.log",
    shell:
        "ballaststudy case assemble {input.bpm} --case {wildcards.case} --rig biaxial "
        "{params.size} --config {params.config} --out {output} --quiet > {log} 2>&1"
