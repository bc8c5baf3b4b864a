"""Objective vs generated parameters of a form database (thesis 3.5, Figs. 3-10 ... 3-16)."""

import numpy as np

from ..standards import GRADING_SIEVES_MM, classify_aggregate, size_diversity


def validation_row(ds):
    """One dict per database: percent passing at every sieve, FI, SI, LI, mass, count, SD,
    generated and objective, and the errors in percentage points."""
    cl = classify_aggregate(ds.a.values, ds.b.values, ds.c.values, ds.mass.values)
    obj_pp = ds.objective_percent_passing.values
    fi_obj = float(ds.attrs["objective_flakiness_index_pct"])
    fi_obj = None if fi_obj < 0 else fi_obj
    row = {
        "database": ds.attrs["database"],
        "particle_count": cl.particle_count,
        "total_mass_kg": cl.total_mass,
        "objective_mass_kg": float(ds.attrs["objective_total_mass_kg"]),
    }
    row["mass_ratio_pct"] = 100.0 * cl.total_mass / row["objective_mass_kg"]
    for s, gen, obj in zip(GRADING_SIEVES_MM, cl.percent_passing, obj_pp):
        row[f"passing_{s:g}mm_pct"] = float(gen)
        row[f"objective_passing_{s:g}mm_pct"] = float(obj)
    row["max_sieve_error_pp"] = float(np.max(np.abs(cl.percent_passing - obj_pp)))
    for key, gen, obj in (("si", cl.shape_index, float(ds.attrs["objective_shape_index_pct"])),
                          ("li", cl.particle_length_index,
                           float(ds.attrs["objective_particle_length_index_pct"])),
                          ("fi", cl.flakiness_index, fi_obj)):
        row[f"{key}_pct"] = float(gen)
        row[f"objective_{key}_pct"] = obj
        row[f"{key}_error_pp"] = None if obj is None else float(abs(gen - obj))
    row["size_diversity"] = cl.size_diversity
    row["objective_size_diversity"] = size_diversity(obj_pp)
    row["grading_categories"] = " ".join(cl.grading_categories) or "none"
    return row


SUMMARY_COLUMNS = ["database", "particle_count", "total_mass_kg", "mass_ratio_pct", "max_sieve_error_pp",
                   "si_pct", "objective_si_pct", "si_error_pp", "li_pct", "objective_li_pct", "li_error_pp",
                   "fi_pct", "objective_fi_pct", "size_diversity", "objective_size_diversity"]
