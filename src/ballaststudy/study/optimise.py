"""The optimised ballast aggregate (thesis 5.8): per-database criteria, a ranking with
settlement first, the Pareto set, the recommended databases, and the thesis' findings of
ch. 5 checked one by one against our numbers (holds / does not hold / not decidable; a study
far below the thesis' scale marks none of them holds or does not hold, see `scale`).

Per-case quantities (one number per (database, case)) are averaged over cases; the spread
over cases is carried as the standard error and, for the findings, as bootstrap intervals
that resample cases within each database (seeded)."""

import numpy as np
import pandas as pd

from . import scale, stats
from .aggregate import database_order_key

# name, variable, per-case quantity, better direction, meaning
CRITERIA = [
    ("settlement_final", "settlement", stats.final_value, "min", "final settlement (m)"),
    ("breakage_rate_final", "breakage_rate", stats.final_value, "min", "final breakage rate (1)"),
    ("ghost_level", "ghost_particles", stats.level_value, "min", "ghost particles, mean over cycles"),
    ("ghost_variability", "ghost_particles", stats.variability_value, "min", "ghost particles, sd over cycles"),
    ("fpa_level", "fpa", stats.level_value, "max", "force propagation angle, mean over cycles (deg)"),
    ("fpa_variability", "fpa", stats.variability_value, "min", "force propagation angle, sd over cycles (deg)"),
    ("void_ratio_level", "void_ratio", stats.level_value, "max", "void ratio, mean over cycles (1)"),
    ("void_ratio_variability", "void_ratio", stats.variability_value, "min", "void ratio, sd over cycles (1)"),
]
DIRECTIONS = {name: d for name, _, _, d, _ in CRITERIA}
TIE_FACTOR = 2.0
RANKING_RULE = (
    "lexicographic with statistical ties, criteria in the order settlement (final), breakage rate (final), "
    "ghost particles (level, then variability), force propagation angle (level, then variability), void ratio "
    "(level, then variability); level = mean over the run cycles, variability = sd over the run cycles, each "
    "averaged over cases. At each criterion the databases still tied are split into tiers: the best remaining "
    f"database and every database within {TIE_FACTOR:g} x sqrt(se_i^2 + se_best^2) of it (se = sd over cases / "
    "sqrt(cases); 0 with one case) form a tier, repeated on the rest; ties left after the last criterion are "
    "ordered by the mean of the per-criterion ranks")
PARETO_OBJECTIVES = {n: d for n, d in DIRECTIONS.items() if n != "void_ratio_variability"}
PARETO_RULE = ("a database is in the Pareto set if no other database is at least as good in every objective "
               f"({', '.join(f'{n} {d}' for n, d in PARETO_OBJECTIVES.items())}; means over cases) and strictly "
               "better in one; databases with a missing objective are not compared")
RECOMMEND_RULE = "per database group, the best-ranked database (the thesis names one per group)"
HIGH_FINES_PCT = 16.0   # thesis 5.2/5.8: at most 16 % passing 22.4 mm
THRESHOLD_RANGE = (16.0, 17.5)
BR_LIMIT = 0.01
JUMP_FACTOR = 1.5
THESIS_FPA_DEG = 55.0     # thesis 5.5: most angles "stay the same (about 55°)"
FPA_TOLERANCE_DEG = 5.0   # our reading of "about": 55 +- 5 deg
# thesis ch. 5's patterns within one database group: key, claim, variable, group, expected
# direction along the group's order (+1 rising, -1 falling, 0 none), databases (None: all)
GROUP_PATTERNS = [
    ("settlement_flat_G_1-2_to_G_1-5", "settlements of G_1-2 to G_1-5 basically the same (5.2)", "settlement",
     "1", 0, ("G_1-2", "G_1-3", "G_1-4", "G_1-5")),
    ("gp_falls_group_1", "ghost particles fall with the mean size, G_1-1 to G_1-5 (5.4)", "ghost_particles", "1",
     -1, None),
    ("gp_rises_group_2", "ghost particles rise with the small stones' share, G_2-1 to G_2-5 (5.4)",
     "ghost_particles", "2", +1, None),
    ("gp_rises_group_3", "ghost particles rise with the share of flat stones, G_3-1 to G_3-5 (5.4)",
     "ghost_particles", "3", +1, None),
    ("vr_shape_none", "the shape distribution, G_3-1 to G_3-5, does not influence the void ratio greatly (5.6)",
     "void_ratio", "3", 0, None),
]
DIRECTION_WORDS = {+1: "positive", -1: "negative", 0: "none"}


def case_table(study):
    """{criterion: (database, case) array} of the per-case quantities."""
    return {name: fn(study[var].values) for name, var, fn, _, _ in CRITERIA}


def database_summary(study):
    """DataFrame indexed by database: group, fines, mean size, and per criterion mean, se, n."""
    per_case = case_table(study)
    df = pd.DataFrame(index=pd.Index([str(d) for d in study.database.values], name="database"))
    df["group"] = [str(g) for g in study.group.values]
    df["percent_passing_22_4mm"] = study.percent_passing_22_4mm.values
    df["mean_size"] = study.mean_size.values
    df["size_diversity"] = study.size_diversity.values
    df["shape_index"] = study.shape_index.values
    for name, values in per_case.items():
        m, se, n = stats.case_mean_se(values)
        df[name], df[f"{name}_se"], df[f"{name}_n"] = m, se, n
    return df


def _tiers(names, mean, se, direction):
    """Split `names` into tiers of statistically tied databases (see RANKING_RULE)."""
    sign = 1.0 if direction == "min" else -1.0
    rest = sorted(names, key=lambda n: (not np.isfinite(mean[n]), sign * mean[n] if np.isfinite(mean[n]) else 0, n))
    tiers = []
    while rest:
        best = rest[0]
        if not np.isfinite(mean[best]):
            tiers.append(rest)
            break
        se_b = se[best] if np.isfinite(se[best]) else 0.0
        tier = [n for n in rest if np.isfinite(mean[n]) and
                sign * (mean[n] - mean[best]) <= TIE_FACTOR * np.hypot(se_b, se[n] if np.isfinite(se[n]) else 0.0)]
        tiers.append(tier)
        rest = [n for n in rest if n not in tier]
    return tiers


def rank_databases(summary, criteria=None):
    """Ranking by RANKING_RULE. Returns `summary` sorted best first with columns rank,
    tier_path (tier per criterion, 1 = best) and mean_criterion_rank."""
    criteria = criteria or [c[0] for c in CRITERIA]
    names = list(summary.index)
    ranks = pd.DataFrame({c: (summary[c] if DIRECTIONS.get(c, "min") == "min" else -summary[c]).rank(
        method="average", na_option="bottom") for c in criteria})
    mean_rank = ranks.mean(axis=1)
    paths = {n: [] for n in names}

    def order(subset, k):
        if len(subset) <= 1 or k == len(criteria):
            return sorted(subset, key=lambda n: (mean_rank[n], database_order_key(n)))
        c = criteria[k]
        out = []
        for t, tier in enumerate(_tiers(subset, summary[c], summary.get(f"{c}_se", pd.Series(0.0, index=names)),
                                        DIRECTIONS.get(c, "min"))):
            for n in tier:
                paths[n].append(t + 1)
            out += order(tier, k + 1)
        return out

    ordered = order(names, 0)
    table = summary.loc[ordered].copy()
    table.insert(0, "rank", np.arange(1, len(ordered) + 1))
    table.insert(1, "tier_path", [".".join(map(str, paths[n])) for n in ordered])
    table.insert(2, "mean_criterion_rank", mean_rank[ordered].values)
    return table


def pareto_set(table, objectives=None):
    """Names (index labels) of the non-dominated rows; objectives {column: 'min'|'max'}."""
    objectives = objectives or PARETO_OBJECTIVES
    cols = list(objectives)
    v = table[cols].to_numpy(float) * np.array([1.0 if objectives[c] == "min" else -1.0 for c in cols])
    ok = np.all(np.isfinite(v), axis=1)
    idx = np.flatnonzero(ok)
    out = []
    for i in idx:
        dominated = any(np.all(v[j] <= v[i]) and np.any(v[j] < v[i]) for j in idx if j != i)
        if not dominated:
            out.append(table.index[i])
    return out


def recommended(ranking):
    """{group: best-ranked database of the group} (RECOMMEND_RULE)."""
    out = {}
    for name, row in ranking.iterrows():
        out.setdefault(row["group"], name)
    return out


# ------------------------------------------------------------------ findings


HOLDS, FAILS, UNDECIDED = "holds", "does not hold", "not decidable"
UNDECIDED_AT_SCALE = "not decidable at this scale"


def _finding(key, claim, mark, rule, numbers):
    # mark_by_rule: the rule's mark on these numbers; `mark` differs from it only below the thesis' scale
    return {"finding": key, "claim": claim, "mark": mark, "mark_by_rule": mark, "rule": rule, "numbers": numbers}


def _at_scale(findings, study):
    """Far below the thesis' scale (scale.SCALE_RULE) a rule's holds / does not hold says
    nothing about the thesis' findings after 1000 cycles over 10 cases: such marks become
    UNDECIDED_AT_SCALE (mark_by_rule keeps them)."""
    if scale.far_below(*scale.extent(study)):
        for f in findings:
            if f["mark"] in (HOLDS, FAILS):
                f["mark"] = UNDECIDED_AT_SCALE
    return findings


def three_way(lo, hi):
    """holds if the interval lies above 0, does not hold if below, else not decidable."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return UNDECIDED
    return HOLDS if lo > 0 else FAILS if hi < 0 else UNDECIDED


def _fmt(v, d=3):
    return "nan" if v is None or not np.isfinite(v) else f"{v:.{d}g}"


def _settlement_jump(ctx, target):
    claim = f"settlement jump for {target}: its settlement is far above the rest of its group"
    rule = (f"statistic S({target}) - {JUMP_FACTOR:g} x max S(other databases of the group), S = final settlement "
            "mean over cases; 95 % bootstrap interval (cases resampled within databases): holds if above 0, does not "
            "hold if below 0, not decidable if it straddles 0, if the database or fewer than 2 others of its group "
            "are present, or any of them has fewer than 2 cases")
    s = ctx["summary"]
    if target not in s.index:
        return _finding(f"jump_{target}", claim, UNDECIDED, rule, f"database {target} missing")
    others = [d for d in s.index[s.group == s.loc[target, "group"]] if d != target]
    counts = s.loc[[target] + others, "settlement_final_n"]
    if len(others) < 2 or (counts < 2).any():
        return _finding(f"jump_{target}", claim, UNDECIDED, rule,
                        f"{len(others)} other databases in group {s.loc[target, 'group']}; cases: "
                        + ", ".join(f"{d} {int(n)}" for d, n in counts.items()))
    boot = ctx["boot"]("settlement_final")
    i, js = ctx["index"][target], [ctx["index"][d] for d in others]
    stat = boot[:, i] - JUMP_FACTOR * np.max(boot[:, js], axis=1)
    lo, hi = stats.interval(stat)
    point = s.loc[target, "settlement_final"] - JUMP_FACTOR * s.loc[others, "settlement_final"].max()
    return _finding(f"jump_{target}", claim, three_way(lo, hi), rule,
                    f"S({target}) = {_fmt(s.loc[target, 'settlement_final'])} m, max of others = "
                    f"{_fmt(s.loc[others, 'settlement_final'].max())} m; statistic {_fmt(point)} m "
                    f"[{_fmt(lo)}, {_fmt(hi)}]")


def fines_threshold(ctx):
    """Two-segment fit of final settlement vs percent passing 22.4 mm across databases."""
    s = ctx["summary"]
    ok = np.isfinite(s.settlement_final) & np.isfinite(s.percent_passing_22_4mm)
    x = s.percent_passing_22_4mm[ok].to_numpy()
    fit = stats.two_segment_fit(x, s.settlement_final[ok].to_numpy())
    if fit is None:
        return None
    boot = ctx["boot"]("settlement_final")[:, ok.to_numpy()]
    boot = boot[np.all(np.isfinite(boot), axis=1)]
    bf = stats.two_segment_fit(x, boot)
    return {"x": x, "y": s.settlement_final[ok].to_numpy(), "fit": fit,
            "breakpoint_ci": stats.interval(bf["breakpoint"]), "excess_ci": stats.interval(bf["excess"])}


def _fines_finding(ctx):
    lo_r, hi_r = THRESHOLD_RANGE
    claim = (f"fines threshold: settlement changes regime between {lo_r:g} and {hi_r:g} % passing 22.4 mm")
    rule = ("two-segment piecewise-linear fit (free jump) of the final settlement (mean over cases) vs percent "
            "passing 22.4 mm across databases, breakpoint = midpoint of the best gap between adjacent databases; "
            "excess = mean of the settlement above the breakpoint minus the lower segment's line extrapolated; 95 % "
            "bootstrap intervals (cases resampled within databases, data refitted): holds if the excess interval "
            f"lies above 0 and the breakpoint interval overlaps [{lo_r:g}, {hi_r:g}] % and is at most 10 points "
            "wide; does not hold if the excess interval lies at or below 0, or the excess is positive and the "
            "breakpoint interval misses the range; not decidable otherwise, with fewer than 4 databases or no "
            "database on each side of the range")
    s = ctx["summary"]
    x = s.percent_passing_22_4mm[np.isfinite(s.settlement_final)]
    if len(x) < 4 or not (x <= lo_r).any() or not (x >= hi_r).any():
        return _finding("fines_threshold", claim, UNDECIDED, rule,
                        f"{len(x)} databases; percent passing 22.4 mm: {', '.join(_fmt(v) for v in sorted(x))}")
    ft = ctx["fines"]
    if ft is None:
        return _finding("fines_threshold", claim, UNDECIDED, rule, "fewer than 4 distinct percent passing values")
    (blo, bhi), (elo, ehi) = ft["breakpoint_ci"], ft["excess_ci"]
    overlaps = blo <= hi_r and bhi >= lo_r
    if ehi <= 0:
        mark = FAILS
    elif elo > 0:
        mark = (HOLDS if bhi - blo <= 10.0 else UNDECIDED) if overlaps else FAILS
    else:
        mark = UNDECIDED
    f = ft["fit"]
    return _finding("fines_threshold", claim, mark, rule,
                    f"breakpoint {_fmt(f['breakpoint'])} % [{_fmt(blo)}, {_fmt(bhi)}] (best gap {_fmt(f['gap_lo'])}"
                    f"-{_fmt(f['gap_hi'])} %); slope below {_fmt(f['left_b'])} m/%, above {_fmt(f['right_b'])} m/%; "
                    f"excess {_fmt(f['excess'])} m [{_fmt(elo)}, {_fmt(ehi)}]")


def _monotone(ctx, key, claim, x, y, sign, what):
    rule = ("Spearman's rho over all (database, case) samples with its 95 % bootstrap interval "
            f"({ctx['n_boot']} resamples): holds if the verdict ({stats.VERDICT_RULE.split(';')[0]} ...) is "
            f"{'positive' if sign > 0 else 'negative'}; does not hold if the interval excludes a "
            f"{'positive' if sign > 0 else 'negative'} rho of at least {stats.MIN_ABS_RHO:g} in size; "
            f"not decidable otherwise or with fewer than {stats.MIN_SAMPLES} samples")
    c = stats.correlation(x, y, n_boot=ctx["n_boot"], seed=ctx["seed"])
    v = stats.verdict(c)
    if v == "not decidable":
        mark = UNDECIDED
    elif v == ("positive" if sign > 0 else "negative"):
        mark = HOLDS
    elif (sign > 0 and c["spearman_hi"] < stats.MIN_ABS_RHO) or (sign < 0 and c["spearman_lo"] > -stats.MIN_ABS_RHO):
        mark = FAILS
    else:
        mark = UNDECIDED
    return _finding(key, claim, mark, rule, f"{what}: n = {c['n']}, rho = {_fmt(c['spearman_rho'])} "
                    f"[{_fmt(c['spearman_lo'])}, {_fmt(c['spearman_hi'])}], Pearson r = {_fmt(c['pearson_r'])}")


def _per_sample(study, coord):
    return np.broadcast_to(study[coord].values[:, None], (study.sizes["database"], study.sizes["case"])).ravel()


def _fpa_finding(ctx):
    claim = (f"force propagation angle stable except in high-fines databases (> {HIGH_FINES_PCT:g} % passing "
             "22.4 mm, e.g. G_1-1 and G_2-5)")
    rule = ("variability = sd of the FPA over the run cycles, mean over cases; statistic min(variability of "
            "high-fines databases) - max(variability of the others), 95 % bootstrap interval (cases resampled "
            "within databases): holds if above 0, does not hold if below 0, not decidable if it straddles 0, with no "
            "high-fines database, fewer than 2 others, or a database with fewer than 2 cases")
    s = ctx["summary"]
    s = s[np.isfinite(s.fpa_variability)]
    high = list(s.index[s.percent_passing_22_4mm > HIGH_FINES_PCT])
    low = list(s.index[s.percent_passing_22_4mm <= HIGH_FINES_PCT])
    if not high or len(low) < 2 or (s.fpa_variability_n < 2).any():
        return _finding("fpa_stability", claim, UNDECIDED, rule,
                        f"high-fines databases: {', '.join(high) or 'none'}; others: {len(low)}")
    boot = ctx["boot"]("fpa_variability")
    ih, il = [ctx["index"][d] for d in high], [ctx["index"][d] for d in low]
    lo, hi = stats.interval(np.min(boot[:, ih], axis=1) - np.max(boot[:, il], axis=1))
    return _finding("fpa_stability", claim, three_way(lo, hi), rule,
                    f"variability (deg): high fines {', '.join(f'{d} {_fmt(s.fpa_variability[d])}' for d in high)}; "
                    f"max of the others {_fmt(s.fpa_variability[low].max())}; statistic "
                    f"{_fmt(s.fpa_variability[high].min() - s.fpa_variability[low].max())} [{_fmt(lo)}, {_fmt(hi)}]")


def _breakage_finding(ctx, study):
    claim = f"breakage rate below {100 * BR_LIMIT:g} % in every database, without trend within the groups"
    rule = (f"level: each database's final breakage rate (mean over cases) with its 95 % bootstrap interval; "
            f"below {100 * BR_LIMIT:g} % if every upper bound is, above if any lower bound is. Trend: per group with "
            "at least 3 databases, Spearman's rho of the final breakage rate of every (database, case) vs the "
            f"database's order in the group, verdict rule as in the IRI tables. Holds if below the limit and no "
            "group shows a trend (at least one group tested); does not hold if above the limit or any group shows a "
            "trend; not decidable otherwise")
    s = ctx["summary"]
    boot = ctx["boot"]("breakage_rate_final")
    present = [d for d in s.index if np.isfinite(s.breakage_rate_final[d])]
    if not present:
        return _finding("breakage_low_no_trend", claim, UNDECIDED, rule, "no breakage data")
    ci = {d: stats.interval(boot[:, ctx["index"][d]]) for d in present}
    level = FAILS if any(lo >= BR_LIMIT for lo, _ in ci.values()) else \
        HOLDS if all(hi < BR_LIMIT for _, hi in ci.values()) else UNDECIDED
    final = stats.final_value(study["breakage_rate"].values)
    trends, tested = [], 0
    for g, members in s.groupby("group"):
        if len(members) < 3:
            continue
        c = _order_correlation(ctx, final, members.index)
        v = stats.verdict(c)
        if v != "not decidable":
            tested += 1
            trends.append(f"group {g}: rho {_fmt(c['spearman_rho'])} [{_fmt(c['spearman_lo'])}, "
                          f"{_fmt(c['spearman_hi'])}] {v}")
    trend_found = any(t.endswith(("positive", "negative")) for t in trends)
    if level == FAILS or trend_found:
        mark = FAILS
    elif level == HOLDS and tested:
        mark = HOLDS
    else:
        mark = UNDECIDED
    worst = max(present, key=lambda d: s.breakage_rate_final[d])
    return _finding("breakage_low_no_trend", claim, mark, rule,
                    f"largest final BR {worst} {_fmt(100 * s.breakage_rate_final[worst])} % "
                    f"[{_fmt(100 * ci[worst][0])}, {_fmt(100 * ci[worst][1])}] %; level {level}; "
                    + ("; ".join(trends) if trends else "no group testable for a trend"))


def _order_correlation(ctx, values, databases):
    """Spearman's rho (with its bootstrap interval) of a per-case value (database, case)
    against each database's place in its group's order, over every (database, case)."""
    order = sorted(databases, key=database_order_key)
    x = np.concatenate([np.full(values.shape[1], k) for k, _ in enumerate(order)])
    y = np.concatenate([values[ctx["index"][d]] for d in order])
    return stats.correlation(x, y, n_boot=ctx["n_boot"], seed=ctx["seed"])


def _group_pattern(ctx, study, key, claim, variable, group, sign, databases):
    word = DIRECTION_WORDS[sign]
    rule = (f"Spearman's rho of the final {variable.replace('_', ' ')} of every (database, case) vs the "
            f"database's place in group {group}'s order, 95 % bootstrap interval, verdict rule as in the IRI "
            f"tables: holds if the verdict is {word}; does not hold if it is "
            + ("positive or negative" if sign == 0 else
               f"{'negative' if sign > 0 else 'positive'} or the interval excludes a {word} rho of at least "
               f"{stats.MIN_ABS_RHO:g} in size")
            + "; not decidable otherwise or with fewer than 3 of the group's databases")
    s = ctx["summary"]
    members = [d for d in (databases or s.index[s.group == group]) if d in s.index]
    if len(members) < 3:
        return _finding(key, claim, UNDECIDED, rule, f"{len(members)} of group {group}'s databases present")
    c = _order_correlation(ctx, stats.final_value(study[variable].values), members)
    v = stats.verdict(c)
    if v == "not decidable":
        mark = UNDECIDED
    elif v == word:
        mark = HOLDS
    elif sign == 0 or v != "none" or (c["spearman_hi"] if sign > 0 else -c["spearman_lo"]) < stats.MIN_ABS_RHO:
        mark = FAILS
    else:
        mark = UNDECIDED
    return _finding(key, claim, mark, rule, f"{', '.join(sorted(members, key=database_order_key))}: n = {c['n']}, "
                    f"rho = {_fmt(c['spearman_rho'])} [{_fmt(c['spearman_lo'])}, {_fmt(c['spearman_hi'])}], {v}")


def _fpa_level_finding(ctx):
    lo_d, hi_d = THESIS_FPA_DEG - FPA_TOLERANCE_DEG, THESIS_FPA_DEG + FPA_TOLERANCE_DEG
    claim = (f"force propagation angle about {THESIS_FPA_DEG:g} deg along the cycles in the databases without "
             f"high fines (5.5)")
    rule = (f"level = FPA mean over the run cycles, mean over cases, 95 % bootstrap interval per database with at "
            f"most {HIGH_FINES_PCT:g} % passing 22.4 mm: holds if every interval lies within [{lo_d:g}, {hi_d:g}] "
            "deg (our reading of 'about'); does not hold if one lies wholly outside; not decidable otherwise or "
            "with no such database")
    s = ctx["summary"]
    low = [d for d in s.index if s.percent_passing_22_4mm[d] <= HIGH_FINES_PCT and np.isfinite(s.fpa_level[d])]
    if not low:
        return _finding("fpa_about_55", claim, UNDECIDED, rule, "no database without high fines")
    boot = ctx["boot"]("fpa_level")
    ci = {d: stats.interval(boot[:, ctx["index"][d]]) for d in low}
    inside = [lo >= lo_d and hi <= hi_d for lo, hi in ci.values()]
    outside = [hi < lo_d or lo > hi_d for lo, hi in ci.values()]
    mark = FAILS if any(outside) else HOLDS if all(inside) else UNDECIDED
    lowest, highest = min(low, key=lambda d: s.fpa_level[d]), max(low, key=lambda d: s.fpa_level[d])
    return _finding("fpa_about_55", claim, mark, rule,
                    f"{len(low)} databases; lowest {lowest} {_fmt(s.fpa_level[lowest])} deg "
                    f"[{_fmt(ci[lowest][0])}, {_fmt(ci[lowest][1])}], highest {highest} {_fmt(s.fpa_level[highest])} "
                    f"deg [{_fmt(ci[highest][0])}, {_fmt(ci[highest][1])}]")


THESIS_OPTIMUM = {"1": "G_1-5", "2": "G_2-1", "3": "G_3-1"}


def _optimum_finding(ctx):
    claim = "optimum databases G_1-5, G_2-1, G_3-1 (one per group)"
    rule = ("per group, our recommendation (best-ranked database of the group) is compared with the thesis' "
            "pick: holds if equal in every group; does not hold if in some group the thesis' pick falls in a "
            "worse tier at some criterion than ours (ranking rule); not decidable if they differ only within "
            "statistical ties, or a thesis pick or fewer than 2 databases of its group are present")
    ranking, s = ctx["ranking"], ctx["summary"]
    notes, marks = [], []
    for g, pick in THESIS_OPTIMUM.items():
        members = list(s.index[s.group == g])
        if pick not in s.index or len(members) < 2:
            notes.append(f"group {g}: {pick if pick not in s.index else 'group'} missing")
            marks.append(UNDECIDED)
            continue
        sub = ranking[ranking.group == g]
        ours = sub.index[0]
        if ours == pick:
            marks.append(HOLDS)
            notes.append(f"group {g}: {pick} best-ranked")
        elif ranking.tier_path[ours] == ranking.tier_path[pick]:
            marks.append(UNDECIDED)
            notes.append(f"group {g}: ours {ours}, thesis {pick}, tied (tier path {ranking.tier_path[pick]})")
        else:
            marks.append(FAILS)
            notes.append(f"group {g}: ours {ours} (tiers {ranking.tier_path[ours]}), thesis {pick} "
                         f"(tiers {ranking.tier_path[pick]})")
    mark = FAILS if FAILS in marks else HOLDS if all(m == HOLDS for m in marks) else UNDECIDED
    return _finding("optimum", claim, mark, rule, "; ".join(notes))


def context(study, n_boot=2000, seed=0):
    """Everything the findings and the report share: summary, ranking, cached bootstraps."""
    summary = database_summary(study)
    per_case = case_table(study)
    cache = {}

    def boot(name):
        if name not in cache:
            rng = np.random.default_rng([seed, list(per_case).index(name)])
            cache[name] = stats.bootstrap_database_means(per_case[name], n_boot, rng)
        return cache[name]

    ctx = {"summary": summary, "ranking": rank_databases(summary), "boot": boot, "n_boot": n_boot, "seed": seed,
           "index": {d: i for i, d in enumerate(summary.index)}}
    ctx["fines"] = fines_threshold(ctx)
    return ctx


def check_findings(study, n_boot=2000, seed=0, ctx=None):
    """The thesis' ch. 5 findings, each as dict(finding, claim, mark, mark_by_rule, rule, numbers)."""
    ctx = ctx or context(study, n_boot, seed)
    final = {v: stats.final_value(study[v].values).ravel() for v in ("settlement", "ghost_particles", "void_ratio")}
    return _at_scale([
        _settlement_jump(ctx, "G_1-1"),
        _settlement_jump(ctx, "G_2-5"),
        _fines_finding(ctx),
        _monotone(ctx, "gp_with_settlement", "ghost particles rise with settlement",
                  final["settlement"], final["ghost_particles"], +1, "final GP vs final settlement"),
        _monotone(ctx, "vr_with_mean_size", "void ratio rises with the mean size",
                  _per_sample(study, "mean_size"), final["void_ratio"], +1, "final VR vs mean size"),
        _monotone(ctx, "vr_with_fines", "void ratio falls with the fines (percent passing 22.4 mm)",
                  _per_sample(study, "percent_passing_22_4mm"), final["void_ratio"], -1,
                  "final VR vs percent passing 22.4 mm"),
        _fpa_finding(ctx),
        _fpa_level_finding(ctx),
        _breakage_finding(ctx, study),
        *(_group_pattern(ctx, study, *pattern) for pattern in GROUP_PATTERNS),
        _optimum_finding(ctx),
    ], study)
