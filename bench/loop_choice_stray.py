"""The loop's rule on the formula model of tests/loop/test_coverage.py (one candidate, rate; 7
tests, K = 3 specimens of ours, a lab specimen per test whose offsets have sd 0.002 - like
ours - 0.01 or 0.04): how often it chooses rate with rate planted or nothing planted, and how
often every condition but the last (what the pick leaves within select.STRAY_LIMIT of the
scatter) passes: the rule's pick named, not adopted. A check to rerun when the rule or the
stray changes (checkout: it imports the tests' helpers).

    python bench/loop_choice_stray.py [DRAWS]      # default 40

Measured 2026-12-07 (40 draws; 1.2 min on one core), nothing planted: chosen 0.00 / 0.00 /
0.00 of the draws, named 0.00 / 0.00 / 0.00; rate planted: chosen 0.90 / 0.00 / 0.00, named
0.90 / 0.15 / 0.00 (the stray limit costs the 0.15 chosen at sd 0.01, all of which the report
had flagged unlike ours). Before the rule's bar (select.bar_mse, 72eb9aa): chosen 0.00 / 0.03
/ 0.03 and 0.95 / 0.40 / 0.23.
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.loop.test_select import MEAS_SD, TESTS, _points, _specimens  # noqa: E402
from tests.loop.test_coverage import GRID, _exact_mean  # noqa: E402
from ballaststudy.loop.discrepancy import make_discrepancy, joint_loglik  # noqa: E402
from ballaststudy.loop.select import (held_out_joint, residual_covariances, residual_dof, held_out_plain,  # noqa: E402
                                      scatter_mse, choose, pick)

def draw(planted, seed, k, per_test_sd):
    """(measured y, point_test, cycles, our K specimens' offsets, their plain curves) of one draw."""
    rng = np.random.default_rng(9000 + seed)
    n, pt = _points(rng)
    theta = 0.2 + 0.6 * rng.random()
    lab = rng.normal(0, per_test_sd, TESTS)[None]
    y = _specimens(rng, n, pt, planted, theta if planted else 0.0, 1, lab)[0] + rng.normal(0, MEAS_SD, len(n))
    offsets = rng.normal(0, 0.002, (k, TESTS))
    return y, pt, n, offsets, _specimens(rng, n, pt, None, 0.0, k, offsets)

def run(planted, draws, sd, k=3):
    """(share of draws the rule chose rate, share in which every condition but the stray
    limit passed: the rule's pick named, not adopted, where the curves stray)."""
    chosen = named = 0
    for seed in range(draws):
        y, pt, n, offsets, plain = draw(planted, seed, k, sd)
        covs, plain_covs = residual_covariances(plain, pt, MEAS_SD ** 2)
        mean = _exact_mean("rate", n, pt, offsets)
        disc = make_discrepancy(y, n, pt, ["lab"] * TESTS)
        held = held_out_plain(plain, y, pt, plain_covs, residual_dof(k), disc)
        sc = scatter_mse(plain_covs, pt, disc)
        joint = joint_loglik(y[None] - mean, np.zeros_like(mean), covs, pt, disc, residual_dof(k))
        cand = held_out_joint(GRID, mean, joint, pt, disc)
        c, ev = choose({"rate": (cand, held)}, y, {"rate": sc})
        chosen += c is not None
        named += pick(ev, 1, alike=False) is not None
    return chosen / draws, named / draws

if __name__ == "__main__":
    draws = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    for planted in (None, "rate"):
        for sd in (0.002, 0.01, 0.04):
            c, u = run(planted, draws, sd)
            print(f"planted {planted or 'none':4s} lab sd {sd:.3f}: chosen {c:.2f} of draws, "
                  f"every condition but the stray limit {u:.2f}", flush=True)
