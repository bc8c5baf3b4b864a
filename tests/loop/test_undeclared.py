"""Data with an undeclared effect (issue 14): model-made "measured" tests with one candidate
effect at a strength the data do not state (loop/synthetic.py), digitised like the shared
data. The goal: the loop names that effect and cuts the held-out RMSE by at least half; on
the plain model plus noise (the negative control) it chooses nothing and leaves the model
unchanged. Slow (11 min on 2 cores): the five scenarios share one case cache (the
candidates' design sets run once; each scenario adds its truth's cases).

The negative control is asserted, and so are rate, abrasion and fouling, whose goal is met.
End restraint is named but its held-out RMSE falls by only a fifth at this scale (3
specimens of 24 synthetic stones, 24 cycles, 8 tests, 9 design sets): a strict xfail, which
fails the suite the day it is met. Measured (bench/loop_undeclared.py at its defaults):
  - rate: chosen (8/8 better, p 0.004), held-out RMSE -62 %;
  - abrasion: chosen (7/8, p 0.008, fitted 0.117 for the planted 0.12), held-out RMSE -68 %;
  - fouling: chosen (8/8, p 0.004), held-out RMSE -62 %;
  - end restraint: chosen (8/8, p 0.004), held-out RMSE -21 %: on 7 tests its error is
    0.09-0.28 of the plain model's, on the p = 25 kPa test 0.82.

Why end restraint falls short here: the truth is one chaotic run of the specimens (DEM is
chaotic: the same run from velocities perturbed by 1e-9 m/s parts from it), and no
prediction made from runs at other parameter values can know that draw. The truth's
irreducible RMSE (synthetic.irreducible_rmse: its chaos, from the truth run again from 3
perturbations, plus the digitiser's noise) is 0.45 of the plain model's for end restraint
- on the p = 25 kPa test, where one specimen of three nearly gives way, 0.47 - against
0.27 (rate), 0.17 (abrasion), 0.06 (fouling). Halving end restraint's error needs a
prediction on the chaos-free trend to within 0.22 of the plain error; the loop's surrogate,
built on design sets that carry chaos of their own, is at 0.79.

Designs screened by the same measure (irreducible / plain RMSE for rate, abrasion, fouling,
end restraint; truths and plain model only, no loop; 3 probes):
  - landed (p 25-60 kPa, q 10-50):     0.27 0.17 0.06 0.45
  - every p + 10 kPa:                  0.71 0.25 0.08 0.06
  - every p + 25 kPa:                  0.77 0.23 0.10 0.06
  - q_max = p:                         0.56 0.20 0.15 0.07
  - q_max = 1.2 p:                     0.52 0.13 0.08 0.04
  - q_max = 40 kPa:                    0.57 0.15 0.09 0.23
  - landed, 4x the stones, 12 cycles:  0.50 0.30 0.13 0.31
  - landed, 48 cycles:                 0.24 0.14 0.07 0.30
(6 specimens instead of 3, one probe: abrasion 0.90 - the 3 added specimens give way.)
Rate's truth (real-time loading at f) carries chaos of about 3e-5 whatever the design, and
only the landed design's low-pressure tests make its signal large against it; end
restraint's signal is large where a specimen nearly gives way, the tests that make its
truth chaotic. The loop's earlier runs on these designs follow the screen where an effect's
floor is high (rate not chosen at p + 25 kPa).
A low floor is necessary, not sufficient: at 48 cycles, every floor 0.30 or below, this test
(17.5 min) chose abrasion for rate (rate 8/8 better, -72 %, but abrasion's summed gain
larger), fouling -34 %, end restraint -25 %; abrasion -78 % and the negative control held.
On another library (seed 4) the landed design met three of the four effects, another one
missing (rate taken for end restraint)."""
from pathlib import Path

import pytest
import yaml

from ballaststudy.loop.synthetic import run_scenario, scenario_setup

ROOT = Path(__file__).resolve().parents[2]
CASES, CYCLES, DESIGN_SETS = 3, 24, 9

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def scenarios(tmp_path_factory):
    folder = tmp_path_factory.mktemp("undeclared")
    specimens, _, _ = scenario_setup(folder, ROOT / "config" / "config.yaml", cases=CASES, cycles=CYCLES,
                                     design_sets=DESIGN_SETS)
    return folder, specimens


def test_negative_control_changes_nothing(scenarios):
    folder, specimens = scenarios
    chosen, candidates, _ = run_scenario(folder, "none", specimens, CYCLES)
    assert chosen is None, candidates
    assert yaml.safe_load((folder / "none" / "loop" / "chosen.yaml").read_text())["effect"] == "none"
    assert not any(c["chosen"] for c in candidates)


GOAL_NOT_MET = pytest.mark.xfail(strict=True, raises=AssertionError,
                                  reason="issue 14: end restraint is chaos-limited at this scale "
                                         "(the truth's irreducible RMSE 0.45 of the plain model's)")


def _named_and_halved(folder, specimens, effect):
    chosen, candidates, plain = run_scenario(folder, effect, specimens, CYCLES)
    evidence = {c["effect"]: c for c in candidates}
    print(f"{effect}: chosen {chosen}; " + "; ".join(
        f"{c['effect']} {c['wins']}/{c['tests']} better, p {c['p']:.3g}, held-out RMSE "
        f"{c['held_out_rmse']:.3g} (plain {plain:.3g})" for c in candidates))
    assert chosen == effect, evidence
    assert evidence[effect]["held_out_rmse"] <= 0.5 * plain, (evidence[effect], plain)


@pytest.mark.parametrize("effect", ["rate", "abrasion", "fouling"])
def test_planted_effect_is_named_and_halves_the_held_out_error(scenarios, effect):
    _named_and_halved(*scenarios, effect)


@pytest.mark.parametrize("effect", ["end_restraint"])
@GOAL_NOT_MET
def test_not_yet_named_and_halved(scenarios, effect):
    _named_and_halved(*scenarios, effect)
