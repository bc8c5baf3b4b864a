"""What the data can tell (issue 75): the discrepancy's size per source beside each
effect's, a fitted interval read against its design range, the smallest effect the rule
would choose on this design, how far the measured specimens stray from the model's, and
the verdict's class.

The smallest detectable effect is an argued approximation, not a power curve: each
candidate's surrogate at a grid of its parameter stands in for the measured points (no
noise, no chaos: the design's expected data), and the rule (select.choose, the Bonferroni
correction over every candidate tried) is run on them against the plain model under the
run's own noise model and discrepancy. An effect that passes on its expected data is chosen
about half the time (its noise moves the evidence either way); the coverage check by
simulation (bench/loop_coverage.py) measures it. Its size is the root mean square of the
surrogate's curve minus the plain ensemble's mean over the measured points: one unit for
every candidate, the one the discrepancy's size is given in."""
import numpy as np

from ..scenario.modifiers import MODIFIERS
from .discrepancy import joint_loglik, source_beta
from .select import STRAY_LIMIT, choose, held_out_joint, held_out_plain, stray as candidate_stray

GRID = 9            # parameter values per candidate the detectable size is read at
EDGE_SHARE = 0.02   # an interval end this close to a bound (share of the range) is at the edge
# an interval this share of the prior's 90 % width or wider is not read as excluding a value
# or as pressing on an edge: it says little (a uniform posterior's 90 % interval never holds
# a bound, and touches one by chance)
INFORMATIVE = 0.5


def _rms(v):
    return float(np.sqrt(np.mean(np.square(v)))) if np.size(v) else float("nan")


def discrepancy_rows(run):
    """Per source: its terms, prior sd and the discrepancy under the plain model and under
    each candidate at its posterior (mean, sd per term; size: its rms over the source's
    points), beside the candidate's effect size (rms of its curve minus the plain mean)."""
    noise, y, point_test = run.noise, run.targets.y, run.targets.point_test
    disc = noise.disc
    point_source = disc.test_source[point_test]
    plain = source_beta(y - run.plain.prediction, noise.plain_covs, point_test, disc, noise.dof)
    under = {name: source_beta(y - c.sampled.curve, noise.covs_of(name), point_test, disc, noise.dof)
             for name, c in run.selection.candidates.items()}
    rows = []
    for s, source in enumerate(disc.sources):
        sel = point_source == s

        def entry(beta):
            mean, sd = beta[s]
            return dict(mean=mean.tolist(), sd=sd.tolist(), size=_rms(disc.basis[sel] @ mean))
        rows.append(dict(source=source, terms=list(disc.terms), prior_sd=disc.prior_sd[s].tolist(),
                         plain=entry(plain),
                         candidates={name: entry(b) | dict(effect_size=_rms(
                             run.selection.candidates[name].sampled.curve[sel] - run.plain.prediction[sel]))
                             for name, b in under.items()}))
    return rows


def interval_notes(name, mean, interval, material=None):
    """Per parameter of effect ``name``: {width_share: the interval's width over the prior's
    90 % width, at_edge: 'low' / 'high' / '' (an informative interval, INFORMATIVE, with an
    end within EDGE_SHARE of a bound other than the no-effect value: the data ask for more
    than the range allows), no_effect: the value at which the effect is off under the plain
    model's ``material`` values (None: no such value), excludes_no_effect: an informative
    interval without it (None: no such value)}."""
    eff = MODIFIERS[name]
    off = eff.off(material or {}) if eff.off else {}
    notes = []
    for p, (lo, hi) in zip(eff.parameters, interval):
        span = p.high - p.low
        value = off.get(p.name)
        share = float((hi - lo) / (0.9 * span))
        edge = "low" if lo - p.low < EDGE_SHARE * span else "high" if p.high - hi < EDGE_SHARE * span else ""
        if share >= INFORMATIVE or (edge and value == (p.low if edge == "low" else p.high)):
            edge = ""        # wide, or at the bound where the effect is off: an answer inside the range
        # an interval pressed on the bound that is the no-effect value holds it: its 5 % tail
        # cannot reach a bound the posterior piles up on (fouling 1.6e-4 [1.6e-4, 2.3e-4] of 0.9)
        reach = EDGE_SHARE * span if value in (p.low, p.high) else 0.0
        held = value is not None and lo - reach <= value <= hi + reach
        notes.append(dict(parameter=p.name, at_edge=edge, width_share=share, no_effect=value,
                          excludes_no_effect=None if value is None else bool(not held and share < INFORMATIVE)))
    return notes


def detectable(run):
    """{effect: {sizes, values, passes per grid value; smallest: the smallest passing size
    (NaN: none in the range)}} of every one-parameter candidate (module doc)."""
    noise, point_test = run.noise, run.targets.point_test
    plain_mean = run.plain.prediction
    tried = len(run.selection.candidates)
    out = {}
    for name, c in run.selection.candidates.items():
        if c.sampled.samples.shape[1] != 1:
            continue
        s = c.sampled
        p = MODIFIERS[name].parameters[0]
        values = np.linspace(p.low, p.high, GRID)
        rows = []
        for v in values:
            at = int(np.argmin(np.abs(s.samples[:, 0] - v)))
            expected = s.mean[at]
            joint = joint_loglik(expected[None] - s.mean, s.sd, noise.covs, point_test, noise.disc, noise.dof, s.shape)
            held = held_out_joint(s.samples, s.mean, joint, point_test, noise.disc)
            plain = held_out_plain(plain_mean[None], expected, point_test, noise.plain_covs, noise.dof, noise.disc)
            chosen, _ = choose({name: (held, plain)}, expected, {name: noise.scatter_of(name)}, tried)
            rows.append((float(s.samples[at, 0]), _rms(expected - plain_mean), chosen == name))
        passing = [size for _, size, ok in rows if ok]
        out[name] = dict(values=[r[0] for r in rows], sizes=[r[1] for r in rows], passes=[r[2] for r in rows],
                         smallest=min(passing) if passing else float("nan"))
    return out


def specimen_stray(run):
    """{model, ratio, rms, scatter}: the held-out rms residual of the chosen effect (where
    none is chosen: of the model that predicts the held-out tests best, the plain model or a
    candidate - a plain model missing a real effect strays too; each test predicted with what
    the other tests of its source say of the discrepancy) over the root of the scatter of the
    model the run ends with (the K specimens', the measurement's, what the other tests leave
    of the discrepancy): the chosen effect's own (select.candidate_covariances), where none is
    chosen the plain model's - its specimens are the ones the report's "no effect needed"
    speaks for (measured against the best candidate's own instead, a candidate whose sets
    make specimens give way called fresh specimens straying 132 x alike: rate, the planted
    abrasion case of bench/loop_undeclared.py). About 1 where the measured curves are like
    the model's; above STRAY_LIMIT they stray far beyond its specimens' scatter - specimens unlike ours, or an
    effect no candidate makes - and the likelihood's noise, which rests on specimens like
    ours, does not hold (the formula model of tests/loop/test_coverage.py, rate planted, 40
    draws: lab specimens like ours: median 1.04, none beyond, coverage 0.88; 5 x ours: 83 %
    beyond, coverage 0.85; 20 x ours: all beyond, coverage 0.72): a candidate that moves the
    curves the way the measured specimens differ fits them precisely (bench/loop_coverage.py: fresh 24-stone specimens strain 10 to 8000 x the
    loop's 3, and intervals a few per cent wide exclude the no-effect value). Why not
    estimate how far they stray (a term per test with its sd estimated, a random effect):
    tried; on the formula model of tests/loop/test_coverage.py it widened rate's intervals 4
    to 9 x at no gain in coverage, and on DEM truths the intervals still excluded the
    no-effect values - a candidate that softens the model explains softer specimens
    whatever their scatter is called.

    within: {candidate: select.stray of its evidence} of the candidates not chosen whose own
    specimens' scatter holds the curves (at most STRAY_LIMIT): where the plain model's does
    not, such an effect - one that makes specimens scatter as these do
    (rate: real-time loading makes them give way) - is one reading of the stray, unlike
    specimens the other (bench/loop_coverage.py, four plans: rate planted on the loop's own
    specimens strays up to 1,500 x from the plain model's scatter, 7 of 8 beyond the limit,
    and 0.09 to 3.8 x from rate's own)."""
    noise, y, chosen = run.noise, run.targets.y, run.selection.chosen
    models = {"plain": run.plain.held, **{name: c.held for name, c in run.selection.candidates.items()}}
    rms = {name: _rms(y - held.predicted) for name, held in models.items()}
    model = chosen or min(rms, key=rms.get)
    scatter = float(np.sqrt(noise.scatter_of(chosen) if chosen else noise.scatter))
    own = {name: candidate_stray(run.selection.evidence[name]) for name in run.selection.candidates if name != chosen}
    return dict(model=model, ratio=rms[model] / scatter if scatter > 0 else float("inf"), rms=rms[model],
                scatter=scatter, within={name: r for name, r in own.items() if r <= STRAY_LIMIT})


def _within_words(within):
    """The sentence naming the candidates whose own specimens' scatter holds the curves."""
    if not within:
        return ""
    return (" The curves lie within the scatter of " + ", ".join(f"{n}'s own specimens ({r:.2g} x)" for n, r in
                                                                  within.items())
            + ": a third reading is an effect that makes specimens scatter so, too small beside that scatter to be told.")


def verdict(chosen, detect, candidates, stray=None, display=(1.0, ""), named=None):
    """(class, sentence): 'chosen', 'no effect needed', 'cannot tell', or 'no effect needed
    among some, cannot tell for the others' ({effect: detectable row}; candidates: the
    names tried; stray: specimen_stray, beyond STRAY_LIMIT 'cannot tell'; named: the rule's
    pick were the curves like ours (select.pick, alike=False), named in that sentence, not
    adopted). display: (factor, unit) the sentence's quantities are written in, as the
    report's tables (metrics.output.display_scale)."""
    def amount(x):
        return f"{display[0] * x:.3g}" + (f" {display[1]}" if display[1] else "")
    if chosen:
        return "chosen", f"Effect chosen: {chosen}."
    if stray is not None and stray["ratio"] > STRAY_LIMIT and candidates:
        return "cannot tell", (
            f"These data cannot tell: the measured curves stray from the {stray['model']} model's by "
            f"{stray['ratio']:.3g} x the scatter of the plain model's specimens (held-out rms "
            f"{amount(stray['rms'])} against {amount(stray['scatter'])}): specimens unlike ours, or an effect no "
            "candidate makes. The intervals rest on specimens like ours and are no evidence for or against an effect."
            + _within_words(stray.get("within"))
            + (f" {named} passes every other condition of the rule: named, not adopted." if named else ""))
    seen = [n for n in candidates if n in detect and np.isfinite(detect[n]["smallest"])]
    blind = [n for n in candidates if n not in seen]
    if not candidates:
        return "no candidates", "No candidate effect was run: the plain model alone is compared."
    if not seen:
        return "cannot tell", ("These data cannot tell: no candidate, anywhere in its range, would pass the rule on "
                               "this design's expected data; 'none chosen' says nothing about the effects.")
    words = "; ".join(f"{n} from an rms effect of {amount(detect[n]['smallest'])}" for n in seen)
    if not blind:
        return "no effect needed", f"No effect needed: the rule would have chosen {words}; none passed."
    return "partly", (f"No effect needed among {', '.join(seen)} (the rule would have chosen {words}); the data cannot "
                      f"tell for {', '.join(blind)} (no value in its range would pass on this design).")
