"""The loop's coverage by simulation, small (bench/loop_coverage.py as a user runs it): DEM
truths on fresh specimens through the unchanged loop. Slow. The full check and its
results: docs/loop/inference.md."""
import csv
import subprocess
import sys
from pathlib import Path

import pytest
from scipy.stats import binomtest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


def test_the_intervals_cover_at_their_level_where_the_report_trusts_them(tmp_path):
    """10 truths (3 with no effect), rate and end restraint, 12 cycles, 5 design sets; 4 of
    them measured on the loop's own specimens (where its noise model holds: a positive
    control), 6 on fresh ones. Every interval checked against what it should hold (the
    planted value, or the no-effect value of a candidate where nothing is planted) on a
    truth whose specimens the report does not call unlike the loop's is counted; the count
    must be one a 90 % method gives with probability above 1 % (binomial); the own-specimen
    truths must be called alike (else the noise model fails on its own specimens); at most
    one no-effect truth may have an effect chosen (the rule's nominal rate is 5 %); and where
    the report calls the specimens unlike ours its verdict says the data cannot tell (the
    rule adopts nothing beyond the stray limit), its intervals not counted: at the loop's K
    = 3 on 24-stone specimens that is most fresh truths (the full check:
    docs/loop/inference.md).

    Failed at the declaration of the noise the curves carry (synthetic.declared_sd; 8dab28c,
    2026-12-07, 21.6 min on 2 cores): false choices 2 of 3 no-effect truths (rate at stray
    45 x, end restraint at 517 x, both "chosen", read with care); it passed with 1e-5
    declared (54dc55a: 1 of 3). With the rule's bar (72eb9aa: the cut must exceed what the
    candidate leaves; the same truths' runs re-judged from the cache, 7 min): 0 of 3, every
    verdict "cannot tell". Then its coverage clause bound on nothing: all 8 truths, all
    fresh, were called unlike ours (stray 45-3,960 x), 0 intervals trusted; hence the
    own-specimen truths.

    FAILS with them (dc0f72d, 2026-12-07, 18.4 min on 2 cores beside other runs): the 4 own
    truths and one fresh one are called alike (stray 0.61-0.87), their verdicts "no effect
    needed", no false choice (0 of 3); but 0 of their 5 checked intervals hold the value:
    end restraint 1.18-1.19 [1.16-1.18, 1.20] at the high edge of its range (marked) on
    truths with 0.73, 1.03 and none (0.7) planted, rate 0.487 [0.467, 0.505] for 0.658. The
    cause is not found yet. Reconstructed from the truths' loop.nc (end restraint): the sets
    at platen friction 0.6, 0.9 and 1.2 all lock like the plain model, each set's mean
    misses the curves by 2-4e-6 in strain (the noise model's scatter, root of its diagonal:
    3.0e-6; the set at 0.9 closest), yet the log likelihood is 37 nats higher at 1.2 than at
    0.9. Tried and refuted: (a) the GP's lengthscale, at its lower bound (0.02 of the range)
    on 2 of the 8 tests so that the surrogate falls back to the sets' mean between sets -
    floored at the design's spacing, 1.174 [1.153, 1.195] for 0.73; (b) the chaos between
    the sets' means missing from the noise (with a lab specimen no chaos probe is run) -
    their variance added to the diagonal (0.63 of the scatter), 1.182-1.188, as narrow.
    Without the set at friction 0 (where the specimens give way: 20 x the others' strain)
    the posterior moves to the locked set nearest the curves and stays as narrow: 0.874
    [0.786, 0.943], 0.892 [0.863, 0.928], 0.918 [0.890, 0.967] for 0.73, 0.7 (none), 1.03.
    What that says: the posterior piles on a design set whatever the truth; each set's mean
    deviates from the smooth trend by a whole-curve chaos draw, which the GP interpolates
    as signal (its white noise fitted ~1e-8 on most tests) and no per-point noise term
    absorbs - so (c) the GP's white noise fixed at the chaos of a set's mean (the locked
    sets' variance per test) instead of fitted: 1.181 [1.165, 1.196], 1.186 [1.172, 1.198],
    1.189 [1.176, 1.199], and 1.115 [0.896, 1.198] for 1.03 (held): little better. Each
    prototype monkeypatched into select from the truths' loop.nc, no run. (d) The case
    covariances cut to their diagonals: 1.014 [0.562, 1.198] for 0.73 (held), 0.917 [0.896,
    1.020] for 1.03, 1.190 [1.177, 1.199] and 0.999 [0.887, 1.185] for 0.7: wider on 3 of 4,
    one held - the K = 3 covariance's directions are part of it, not all. (e) The same
    check at K = 8 (`python bench/loop_coverage.py OUT --truths 10 --effects rate
    end_restraint --design-sets 5 --cycles 12 --pool 12 --own-share 0.4 --cases 8`; 39.5
    min on 2 cores, 0.56 core-hours; new DEM runs, the same plan): 5 of 7 intervals on
    truths alike ours hold (binomial p vs 0.9 about 0.15: the clause would pass) - end
    restraint 4 of 4 where nothing or it was planted on our own specimens (0.66-1.02, 0.5-0.8
    of the prior wide), missing on a fresh truth (0.134 [0.043, 0.259] for 0.875); rate 0 of
    1 (0.400 [0.347, 0.430] for 0.580) - but the own truth with rate planted strays 15 x
    (unlike ours: real-time loading makes our own specimens give way, a scatter the plain
    model's noise does not hold), so the own-truths-alike clause would fail there. More
    specimens mend end restraint's intervals; rate's are still too narrow.

    Each candidate fitted under its own sets' scatter (select.candidate_covariances,
    419e9af-651f7f1; the method changed, not this design): the K = 3 runs above re-judged
    from their cache, 4 of 5 trusted intervals hold (binomial p 0.41; the miss rate's
    0.449 [0.318, 0.609] for 0.658 on an own truth), the own truths alike, no false choice,
    every unlike verdict "cannot tell" - every clause holds; intervals 0.3-0.7 of the prior
    wide. PASSED from a clean checkout at 651f7f1 (2026-12-07, 16.6 min on 2 cores), the same
    intervals. On other truths (bench/loop_coverage.py --plan-seed 1, the same design, new
    runs) the own-truths clause FAILS: 3 of its 4 own-specimen truths have rate planted and
    stray 8.8-1,527 x from the plain model's scatter (real-time loading makes our own
    specimens give way), verdict "cannot tell"; 1 trusted interval, held. The clause assumes
    an effect that leaves the specimens' scatter as it is; this plan has one rate truth on
    our specimens, and it locked. --plan-seed 2: its two rate truths on our specimens stray
    58 and 262 x, the two with nothing planted are alike and hold. Over the three plans: 6
    of 6 own truths without rate alike, 1 of 6 with rate; 7 of 8 trusted intervals hold
    (docs/loop/inference.md)."""
    out = tmp_path / "coverage"
    subprocess.run([sys.executable, str(ROOT / "bench/loop_coverage.py"), str(out), "--truths", "10", "--effects",
                    "rate", "end_restraint", "--design-sets", "5", "--cycles", "12", "--pool", "12",
                    "--own-share", "0.4"], check=True, cwd=ROOT)
    with open(out / "truths.csv") as f:
        rows = list(csv.DictReader(f))
    trusted = [r for r in rows if r["holds"] != "" and r["unlike"] == "0"]
    held = sum(int(r["holds"]) for r in trusted)
    p = binomtest(held, len(trusted), 0.9).pvalue if trusted else 1.0
    with open(out / "coverage.csv") as f:
        table = {r["planted"]: r for r in csv.DictReader(f)}
    unlike = {r["truth"] for r in rows if r["unlike"] == "1"}
    own = {r["truth"] for r in rows if r["source"] == "own"}
    print(f"\n{held}/{len(trusted)} trusted intervals hold their value (binomial p vs 0.9: {p:.3g}); {len(unlike)}/10 "
          f"truths' specimens unlike ours ({len(unlike & own)} of the {len(own)} on our own); false choices on "
          f"no-effect truths {table['none']['false_choices']}/{table['none']['truths']}")
    assert len(own) == 4 and not unlike & own, sorted(unlike & own)
    assert all(r["verdict"] == "cannot tell" for r in rows if r["truth"] in unlike)
    assert p > 0.01, (held, len(trusted))
    assert int(table["none"]["false_choices"]) <= 1, table["none"]
