"""Data with an undeclared effect (issue 14): model-made "measured" tests with one candidate
effect at a strength the data do not state (loop/synthetic.py), digitised like the shared
data. The loop must name that effect and cut the held-out RMSE by at least half; on the
plain model plus noise (the negative control) it must choose nothing and leave the model
unchanged. Slow (7.5 min on 2 cores): the five scenarios share one case cache (the
candidates' design sets run once; each scenario adds its truth's cases).

Where it stands at this scale (3 specimens of 24 synthetic stones, 12 cycles, 8 tests): the
negative control and rate pass (rate: 8/8 tests better, signed-rank p 0.004, held-out RMSE
-88 %). The other three are marked as expected failures (strict: one that passes turns the
run red, and its mark goes), each for the reason measured: abrasion is recovered (wear
0.121 per cycle for the planted 0.12, held-out RMSE -70 %) but acts on 4 of the 8 tests
only, and four wins with four ties cannot pass 0.05 / 4 (the smallest p is 1/16); fouling
(planted loss 0.6, fitted 0.45) and end restraint (planted friction 0.2, fitted 0.38) are
not followed by the surrogate from five design sets and gain on 1/8 and 0/8 tests. The
verdicts are fragile at this scale: a flat-joint kernel that changed only the rounding
(other trajectories, same physics) moved rate to 6/8 tests, p 1/64, not chosen."""
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


NOT_YET = "not found at this scale (see the module text)"


@pytest.mark.parametrize("effect", [
    "rate",
    pytest.param("abrasion", marks=pytest.mark.xfail(strict=True, reason=NOT_YET)),
    pytest.param("fouling", marks=pytest.mark.xfail(strict=True, reason=NOT_YET)),
    pytest.param("end_restraint", marks=pytest.mark.xfail(strict=True, reason=NOT_YET)),
])
def test_the_planted_effect_is_named_and_halves_the_held_out_error(scenarios, effect):
    folder, specimens = scenarios
    chosen, candidates, plain = run_scenario(folder, effect, specimens, CYCLES)
    evidence = {c["effect"]: c for c in candidates}
    assert chosen == effect, evidence
    assert evidence[effect]["held_out_rmse"] <= 0.5 * plain, (evidence[effect], plain)
