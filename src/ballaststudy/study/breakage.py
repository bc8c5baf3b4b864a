"""Breakage in numbers, from study.nc: how many flat-joint elements each case broke, before
and during the load cycles, and when (thesis 5.3, Figs. 5-2 and 5-3)."""

import numpy as np

from . import stats

# Thesis 5.3 on Fig. 5-3 (mean number of breakages per database over its 10 cases, after the
# 1000 load cycles): "the highest value is just above 8".
THESIS_MAX_MEAN_BREAKAGES = 8.0
BREAKAGE_CYCLES = (1, 10, 100)   # cycles at which the record says how much breakage had happened


def breakage_counts(study):
    """Per case (database, case): broken flat-joint elements at its last run cycle, and of
    them those broken during the load cycles (the rest broke before the first cycle: in the
    static pre-loading, or at the end of the assembly). NaN where a case did not run."""
    total = stats.final_value((study["broken_tension"] + study["broken_shear"]).values)
    per_cycle = study["breakages_per_cycle"].values
    during = np.where(np.isfinite(total), np.nansum(per_cycle, axis=-1), np.nan)
    return total, during


def breakage_timing(study, cycles=BREAKAGE_CYCLES):
    """When and in what units the cases broke, from study.nc: per case that broke, the share
    of its final breakage rate reached by the end of each given cycle (1-based; bonds broken
    in the static pre-loading count in cycle 1's), as medians; the flat-joint elements per
    case (broken / rate at the last cycle) and the broken elements per case. Cases shorter
    than a cycle are left out of its share."""
    br = study["breakage_rate"].values.reshape(-1, study.sizes["cycle"])
    final = stats.final_value(br)
    broke = np.isfinite(final) & (final > 0)
    out = {"cases_broke": int(broke.sum()), "cases_ran": int(np.isfinite(final).sum()), "share": {}}
    for c in cycles:
        if c <= br.shape[1]:
            share = br[broke, c - 1] / final[broke]
            if np.isfinite(share).any():
                out["share"][c] = float(np.nanmedian(share))
    n_broken = breakage_counts(study)[0].reshape(-1)[broke]
    out["elements"] = np.round(n_broken / final[broke]).astype(int)
    out["broken"] = n_broken.astype(int)
    return out
