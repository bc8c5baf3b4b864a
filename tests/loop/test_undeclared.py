"""Data with an undeclared effect (issue 14): model-made "measured" tests with one candidate
effect at a strength the data do not state (loop/synthetic.py), digitised like the shared
data. The goal: the loop names that effect and cuts the held-out RMSE by at least half; on
the plain model plus noise (the negative control) it chooses nothing and leaves the model
unchanged. Slow (5-6 min on 2 cores): the five scenarios share one case cache (the
candidates' design sets run once; each scenario adds its truth's cases).

The negative control is asserted. The goal is not met at this scale (3 specimens of 24
synthetic stones, 12 cycles, 8 tests), so each planted scenario is a strict xfail: it
fails the suite the day the goal is met, to be turned into a plain assertion. Measured
with eight distinct conditions (p differs from test to test; f and VCI not ordered alike):
  - rate: end restraint chosen instead (8/8 better at platen friction ~0, held-out RMSE
    -30 %); rate itself 6/8, p 0.016 > 0.05/4, held-out RMSE -55 %;
  - abrasion: nothing chosen (1/8);
  - fouling: nothing chosen (3/8), though its held-out RMSE is -74 %;
  - end restraint: chosen (7/8, p 0.008, fitted 0.26 for the planted 0.2), held-out RMSE
    -37 %, not -50 %.
Earlier runs that "found" an effect 8/8 (sessions up to 25) had tests sharing p and q:
for every effect but rate those were copies of two runs, and the signed-rank test counted
two conditions as eight. bench/loop_undeclared.py measures the sensitivity."""
from pathlib import Path

import pytest
import yaml

from ballaststudy.loop.synthetic import run_scenario, scenario_setup

ROOT = Path(__file__).resolve().parents[2]
CASES, CYCLES = 3, 12

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


@pytest.mark.parametrize("effect", ["rate", "abrasion", "fouling", "end_restraint"])
@GOAL_NOT_MET
def test_the_planted_effect_is_named_and_halves_the_held_out_error(scenarios, effect):
    folder, specimens = scenarios
    chosen, candidates, plain = run_scenario(folder, effect, specimens, CYCLES)
    evidence = {c["effect"]: c for c in candidates}
    print(f"{effect}: chosen {chosen}; " + "; ".join(
        f"{c['effect']} {c['wins']}/{c['tests']} better, p {c['p']:.3g}, held-out RMSE "
        f"{c['held_out_rmse']:.3g} (plain {plain:.3g})" for c in candidates))
    assert chosen == effect, evidence
    assert evidence[effect]["held_out_rmse"] <= 0.5 * plain, (evidence[effect], plain)
