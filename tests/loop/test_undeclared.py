"""Data with an undeclared effect (issue 14): model-made "measured" tests with one candidate
effect at a strength the data do not state (loop/synthetic.py), digitised like the shared
data. The goal: the loop names that effect and cuts the held-out RMSE by at least half; on
the plain model plus noise (the negative control) it chooses nothing and leaves the model
unchanged. Slow (11 min on 2 cores): the five scenarios share one case cache (the
candidates' design sets run once; each scenario adds its truth's cases).

The negative control is asserted, and so are rate, abrasion and fouling, whose goal is met.
End restraint is named but its held-out RMSE falls by only a fifth at this scale (3
specimens of 24 synthetic stones, 24 cycles, 8 tests, 9 design sets): a strict xfail, which
fails the suite the day it is met. Measured with the noise of model-made data
(specimen_share 0: the chaos of the model's own specimens, from the plain ensemble run again
from perturbed velocities; loop/select.py) and the candidates' design on an even grid from
bound to bound (bench/loop_undeclared.py at its defaults):
  - rate: chosen (8/8 better, p 0.004), held-out RMSE -62 %;
  - abrasion: chosen (7/8, p 0.008, fitted 0.117 for the planted 0.12), held-out RMSE -68 %;
  - fouling: chosen (8/8, p 0.004), held-out RMSE -62 %;
  - end restraint: chosen (8/8, p 0.004), held-out RMSE -21 %: on 7 tests its error is
    0.09-0.28 of the plain model's, but the pooled RMSE is led by the p = 25 kPa test,
    where one plain specimen of three gives way and the chaos alone (1.2e-4) exceeds the
    effect's signal (1.4e-5 on the others): there 0.82.
With 5 design sets (until session 28) the surrogate's variance between sets was wide: at 24
cycles fouling fell -47 % and end restraint was not chosen (6/8: two tests lost density
although their RMSE fell 4-8x); at 12 cycles rate was chosen (-67 %), abrasion at -38 %,
fouling not (7/8, p 0.074), end restraint not (6/8, p 0.27).
Before (the case-to-case scatter, each candidate under its own pooled noise): only end
restraint was chosen, and rate was taken for end restraint. Earlier runs that "found" an
effect 8/8 (sessions up to 25) had tests sharing p and q: for every effect but rate those
were copies of two runs, and the signed-rank test counted two conditions as eight.
bench/loop_undeclared.py measures the sensitivity. Other scales, measured with it at 5 design
sets (planted effect: chosen?, pooled held-out RMSE change; the median over tests of the
per-test ratio):
  - 24 cycles, the p = 25 kPa test at 65: rate not chosen (7/8, p 0.02), abrasion chosen
    -10 % (0.38), fouling chosen -6 % (0.55), end restraint chosen -82 % (0.16);
    with 9 design sets: rate chosen -43 %, abrasion chosen -14 %, fouling chosen +68 %, end
    restraint chosen -79 % (the p = 30 and 35 kPa tests, where a specimen gives way under
    rate, abrasion or fouling, lead those three);
  - 0.24 x 0.48 m specimens (4x the stones), 12 cycles, p 25 -> 65: abrasion chosen -73 %
    (0.25), fouling chosen -40 % (0.67), end restraint chosen -32 % (0.46), rate taken for
    end restraint (gains 5.92e4 against 5.96e4); with 9 design sets: abrasion chosen -77 %,
    end restraint chosen -57 %, rate and fouling taken for end restraint (fouling's gain
    4.90e4 against 4.92e4: on these specimens the platens' friction mimics both);
  - 5 specimens (p 25 -> 65): nothing chosen anywhere (one specimen strains 30-100x the others).
Other test designs at this scale (24 cycles, 9 design sets; session 29, SCENARIO_TESTS
patched, all else as landed):
  - every p + 25 kPa (50-85, q 10-50): rate not chosen (5/8, p 0.12: its design sets'
    errors scatter without a minimum, the rate signal drowned in chaos at these pressures),
    abrasion -69 %, fouling -54 %, end restraint -87 %;
  - q_max = p (one stress ratio, 1.0): rate not chosen (7/8, p 0.02; -54 %), abrasion -85 %,
    fouling -66 %, end restraint not chosen (5/8; -84 %: at the low pressures its signal is
    below the noise, those tests tie);
  - q_max = 1.4 p: rate -68 %, abrasion -81 %, fouling chosen but +85 % (the p = 35 kPa
    test, where a specimen gives way, 2.1x the plain model's error), end restraint taken
    for abrasion (7/8 against 6/8).
Each design names and halves two or three of the four effects; none all four. The landed
design (three of four, with the negative control four of five scenarios) is the best of them.
Another library (SCENARIO_LIBRARY seed 4 instead of 3, the landed design; its specimens
strain about 100x more, several give way): negative control nothing chosen; rate taken for
end restraint (rate's own held-out RMSE -6 %); abrasion -67 %, fouling -91 %, end
restraint -82 %, each named. Three of four effects again, with another one missing: which effect
fails moves with the specimens.
The negative control held at every scale. Which effect passes moves with the scale: the
pooled RMSE is led by the one test where a specimen of three gives way under the effect
(there the held-out prediction misses by up to 0.9x the plain model's error), while per test
the planted effect halves the error on most tests."""
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
                                  reason="issue 14: the loop's sensitivity at this scale is not established")


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
