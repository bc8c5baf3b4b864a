"""Data with an undeclared effect (issue 14): model-made "measured" tests with one candidate
effect at a strength the data do not state (loop/synthetic.py), digitised like the shared
data. The goal: the loop names that effect and cuts the held-out RMSE by at least half; on
the plain model plus noise (the negative control) it chooses nothing and leaves the model
unchanged. Slow (7-8 min on 2 cores): the five scenarios share one case cache (the
candidates' design sets run once; each scenario adds its truth's cases).

The negative control is asserted, and so are rate and abrasion, whose goal is met. The goal
is not met for the other two at this scale (3 specimens of 24 synthetic stones, 24 cycles,
8 tests): each is a strict xfail, which fails the suite the day it is met. Measured with
the noise of model-made data (specimen_share 0: the chaos of the model's own specimens,
from the plain ensemble run again from perturbed velocities; loop/select.py) and the
candidates' design on an even grid from bound to bound (bench/loop_undeclared.py --cycles 24):
  - rate: chosen (8/8 better, p 0.004), held-out RMSE -62 %;
  - abrasion: chosen (8/8, p 0.004, fitted 0.113 for the planted 0.12), held-out RMSE -56 %;
  - fouling: chosen (8/8, p 0.004), held-out RMSE -47 %, not -50 %;
  - end restraint: not chosen (6/8, p 0.02 > 0.05/4), held-out RMSE -14 %.
At 12 cycles (until session 28) rate was chosen (-67 %), abrasion chosen at -38 %, fouling
not chosen (7/8, p 0.074), end restraint not chosen (6/8, p 0.27).
Before (the case-to-case scatter, each candidate under its own pooled noise): only end
restraint was chosen, and rate was taken for end restraint. Earlier runs that "found" an
effect 8/8 (sessions up to 25) had tests sharing p and q: for every effect but rate those
were copies of two runs, and the signed-rank test counted two conditions as eight.
bench/loop_undeclared.py measures the sensitivity. Other scales, measured with it (planted
effect: chosen?, pooled held-out RMSE change; the median over tests of the per-test ratio):
  - 24 cycles, the p = 25 kPa test at 65: rate not chosen (7/8, p 0.02), abrasion chosen
    -10 % (0.38), fouling chosen -6 % (0.55), end restraint chosen -82 % (0.16);
  - 0.24 x 0.48 m specimens (4x the stones), 12 cycles (25 kPa): abrasion chosen -73 % (0.25),
    fouling chosen -40 % (0.67), end restraint chosen -32 % (0.46), rate taken for end
    restraint (gains 5.92e4 against 5.96e4);
  - 5 specimens (p 25 -> 65): nothing chosen anywhere (one specimen strains 30-100x the others).
The negative control held at every scale. Which effect passes moves with the scale: the
pooled RMSE is led by the one test where a specimen of three gives way under the effect
(there the held-out prediction misses by up to 0.9x the plain model's error), while per test
the planted effect halves the error on most tests."""
from pathlib import Path

import pytest
import yaml

from ballaststudy.loop.synthetic import run_scenario, scenario_setup

ROOT = Path(__file__).resolve().parents[2]
CASES, CYCLES = 3, 24

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def scenarios(tmp_path_factory):
    folder = tmp_path_factory.mktemp("undeclared")
    specimens, _, _ = scenario_setup(folder, ROOT / "config" / "config.yaml", cases=CASES, cycles=CYCLES)
    return folder, specimens


def test_negative_control_changes_nothing(scenarios):
    folder, specimens = scenarios
    chosen, candidates, _ = run_scenario(folder, "none", specimens, CYCLES)
    assert chosen is None, candidates
    assert yaml.safe_load((folder / "none" / "loop" / "chosen.yaml").read_text())["effect"] == "none"
    assert not any(c["chosen"] for c in candidates)


GOAL_NOT_MET = pytest.mark.xfail(strict=True, raises=AssertionError,
                                  reason="issue 14: the loop's sensitivity at this scale is not established")


def _named_and_halved(folder, specimens, effect):
    chosen, candidates, plain = run_scenario(folder, effect, specimens, CYCLES)
    evidence = {c["effect"]: c for c in candidates}
    print(f"{effect}: chosen {chosen}; " + "; ".join(
        f"{c['effect']} {c['wins']}/{c['tests']} better, p {c['p']:.3g}, held-out RMSE "
        f"{c['held_out_rmse']:.3g} (plain {plain:.3g})" for c in candidates))
    assert chosen == effect, evidence
    assert evidence[effect]["held_out_rmse"] <= 0.5 * plain, (evidence[effect], plain)


@pytest.mark.parametrize("effect", ["rate", "abrasion"])
def test_planted_effect_is_named_and_halves_the_held_out_error(scenarios, effect):
    _named_and_halved(*scenarios, effect)


@pytest.mark.parametrize("effect", ["fouling", "end_restraint"])
@GOAL_NOT_MET
def test_not_yet_named_and_halved(scenarios, effect):
    _named_and_halved(*scenarios, effect)
