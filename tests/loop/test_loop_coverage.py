"""The loop's coverage by simulation, small (bench/loop_coverage.py as a user runs it): DEM
truths on fresh specimens through the unchanged loop. Slow. The full check and its
results: docs/loop/inference.md."""
import csv
import subprocess
import sys
from pathlib import Path

import pytest
from scipy.stats import binomtest

from ballaststudy.loop.select import STRAY_LIMIT

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


def test_the_intervals_cover_at_their_level_where_the_report_trusts_them(tmp_path):
    """10 truths (3 with no effect), rate and end restraint, 12 cycles, 5 design sets; 4 of
    them measured on the loop's own specimens, 6 on fresh ones. Every interval checked
    against what it should hold (the planted value, or the no-effect value of a candidate
    where nothing is planted) on a truth whose specimens the report does not call unlike the
    loop's is counted; the count must be one a 90 % method gives with probability above 1 %
    (binomial). On the loop's own specimens the model that made the curves must hold them
    (the noise model's positive control): the plain model's scatter where nothing is
    planted, the planted candidate's own scatter where one is (its `own_stray`). At most one
    no-effect truth may have an effect chosen (the rule's nominal rate is 5 %), and where the
    report calls the specimens unlike ours its verdict says the data cannot tell, its
    intervals not counted: at the loop's K = 3 on 24-stone specimens that is most fresh
    truths.

    Measured (docs/loop/inference.md, "How far the intervals can be trusted", with the runs
    before each change): passes from a clean checkout at 651f7f1 (16.6 min on 2 cores), 4 of
    5 trusted intervals hold. The positive control was first "every own truth is called
    alike" (against the plain model's scatter); on other plans (`--plan-seed 1`, `2`) own
    truths with rate planted strayed 9-1,527 x from it - real-time loading makes our own
    specimens give way - so that clause asked the plain model to hold curves made by
    another, and is replaced by the one above. Over plans 0-2 it holds on 11 of 12 own
    truths; it fails on plan 1 (rate planted at 0.067, 3.8 x its own scatter, pooled over
    a design whose other sets scatter less). Rate's intervals on its own truths hold 1 of 6
    (each under "cannot tell" but one)."""
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
    # own truths the model that made them does not hold: the plain model's scatter where nothing is
    # planted, the planted candidate's own where one is
    unheld = ({r["truth"] for r in rows if r["truth"] in own and r["planted"] == "none" and r["unlike"] == "1"}
              | {r["truth"] for r in rows if r["truth"] in own and r["candidate"] == r["planted"]
                 and float(r["own_stray"]) > STRAY_LIMIT})
    print(f"\n{held}/{len(trusted)} trusted intervals hold their value (binomial p vs 0.9: {p:.3g}); {len(unlike)}/10 "
          f"truths' specimens unlike ours ({len(unlike & own)} of the {len(own)} on our own, {len(unheld)} not held "
          f"by the model that made them); false choices on no-effect truths "
          f"{table['none']['false_choices']}/{table['none']['truths']}")
    assert len(own) == 4 and not unheld, sorted(unheld)
    assert all(r["verdict"] == "cannot tell" for r in rows if r["truth"] in unlike)
    assert p > 0.01, (held, len(trusted))
    assert int(table["none"]["false_choices"]) <= 1, table["none"]
