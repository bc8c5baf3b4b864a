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


def test_the_intervals_cover_at_their_level_and_nothing_is_chosen_too_often(tmp_path):
    """8 truths (3 with no effect), rate and end restraint, 12 cycles, 5 design sets: every
    interval checked against what it should hold (the planted value, or the no-effect value
    of a candidate not planted) is counted; the count must be one a 90 % method gives with
    probability above 1 % (binomial), and at most one no-effect truth may have an effect
    chosen (the rule's nominal rate is 5 %)."""
    out = tmp_path / "coverage"
    subprocess.run([sys.executable, str(ROOT / "bench/loop_coverage.py"), str(out), "--truths", "8", "--effects",
                    "rate", "end_restraint", "--design-sets", "5", "--cycles", "12", "--pool", "12"],
                   check=True, cwd=ROOT)
    with open(out / "truths.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["holds"] != ""]
    held = sum(int(r["holds"]) for r in rows)
    p = binomtest(held, len(rows), 0.9).pvalue
    with open(out / "coverage.csv") as f:
        table = {r["planted"]: r for r in csv.DictReader(f)}
    print(f"\n{held}/{len(rows)} intervals hold their value (binomial p vs 0.9: {p:.3g}); "
          f"false choices on no-effect truths {table['none']['false_choices']}/{table['none']['truths']}")
    assert p > 0.01, (held, len(rows))
    assert int(table["none"]["false_choices"]) <= 1, table["none"]
