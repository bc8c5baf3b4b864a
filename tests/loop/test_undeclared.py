"""Data with an undeclared effect (issue 14): model-made "measured" tests with one candidate
effect at a strength the data do not state (loop/synthetic.py), digitised like the shared
data. The goal: the loop names that effect and cuts the held-out RMSE by at least half; on
the plain model plus noise (the negative control) it chooses nothing and leaves the model
unchanged. Slow (6-7.5 min on 2 cores): the five scenarios share one case cache (the
candidates' design sets run once; each scenario adds its truth's cases).

What is asserted, and why not more. At this scale (3 specimens of 24 synthetic stones, 12
cycles, 8 tests) which planted effect is found depends on the trajectories: three flat-joint
kernels that differ only in rounding (same physics, checked on the box case) gave
  - landed at 7d20386: rate chosen (8/8 tests better, p 0.004, held-out RMSE -88 %), the
    other three not (abrasion 4/8 with four ties, fouling 1/8, end restraint 0/8);
  - three-pass kernel: nothing chosen (rate and abrasion 6/8, p 1/64 > 0.05/4);
  - three-pass kernel, Verlet list without bonded pairs: end restraint chosen (8/8,
    p 0.004, fitted friction 0.29 for the planted 0.2, held-out RMSE -76 %), rate 2/8.
So the loop's sensitivity is not established here (bench/loop_undeclared.py measures it;
issue 14 stays open for it), and the suite asserts what held in every run: the negative
control changes nothing, and a planted effect is never mistaken for another (the loop
chooses the planted effect or nothing, and when it chooses, the held-out RMSE halves)."""
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


@pytest.mark.parametrize("effect", ["rate", "abrasion", "fouling", "end_restraint"])
def test_a_planted_effect_is_never_mistaken_for_another(scenarios, effect):
    folder, specimens = scenarios
    chosen, candidates, plain = run_scenario(folder, effect, specimens, CYCLES)
    evidence = {c["effect"]: c for c in candidates}
    assert chosen in (None, effect), evidence
    if chosen == effect:
        assert evidence[effect]["held_out_rmse"] <= 0.5 * plain, (evidence[effect], plain)
    print(f"{effect}: chosen {chosen}; " + "; ".join(
        f"{c['effect']} {c['wins']}/{c['tests']} better, p {c['p']:.3g}"
        for c in candidates))
