"""Specimen sets and the keys a stage overrides: a stage names a set of the rig it runs and
takes at most its cases (one line naming the key otherwise); the rig parameters a measured
test sets itself are found (so editing them in the config reruns nothing), and only those."""
import pytest

from ballaststudy.cli import main
from ballaststudy.scenario.scenario import conditioned_keys
from ..shipped import shipped_config


def _config(tmp_path, change):
    return shipped_config(tmp_path / "config.yaml", change)


@pytest.mark.parametrize("change, key, allowed", [
    (lambda c: c["loop"].update(specimens="box"), "loop.specimens", "'box' is a box set; allowed: a biaxial set"),
    (lambda c: c["parametric"].update(specimens="biaxial_small"), "parametric.specimens", "allowed: a box set"),
    (lambda c: c["measured"]["sim"].update(specimens="large"), "measured.sim.specimens",
     "'large' is not a specimen set; allowed: biaxial_small, box"),
    (lambda c: c["loop"].update(cases=5), "loop.cases", "5, but the set 'biaxial_small' has 3; allowed: at most 3"),
    (lambda c: c["specimens"]["box"].update(width_m=0.3), "specimens.box.width_m", "allowed: null"),
    (lambda c: c["specimens"]["box"].pop("rig"), "specimens.box.rig", "missing"),
    (lambda c: c["loop"].update(effects=["rate", "moisture"]), None, None),      # the loop's own check
])
def test_a_bad_specimen_set_is_one_line(tmp_path, capsys, change, key, allowed):
    config = _config(tmp_path, change)
    code = main(["config", "check", "--config", str(config)])
    if key is None:
        assert code == 0            # config check leaves the loop's effects to the loop (test_cli)
        return
    line = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in line and f"{config}: {key}" in line and allowed in line, line


def test_the_default_sets_pass(tmp_path):
    assert main(["config", "check", "--config", str(_config(tmp_path, lambda c: None))]) == 0


def test_a_set_of_an_unknown_database_is_a_note(tmp_path, capsys):
    """A study of other databases still runs; only the stages using the set cannot."""
    config = _config(tmp_path, lambda c: c["specimens"]["box"].update(database="G_9-9"))
    assert main(["config", "check", "--config", str(config)]) == 0
    err = capsys.readouterr().err.strip()
    assert err.startswith("note: specimens.box.database 'G_9-9' is not in ") and "\n" not in err, err


def _test(**c):
    return dict(source="planted", rig="triaxial", confining_pressure_kPa=30.0, deviator_max_kPa=50.0, **c)


def test_the_keys_a_test_sets_are_found():
    """p and q_max always; q_min and f where every test gives them; a box test's load bounds
    and settlement force, not its preloads (scaled, so the config's still matter)."""
    assert conditioned_keys("biaxial", [_test()]) == ("confining_pressure_kPa", "deviator_max_kPa")
    full = _test(deviator_min_kPa=10.0, frequency_Hz=20.0)
    assert conditioned_keys("biaxial", [full]) == ("confining_pressure_kPa", "deviator_max_kPa",
                                                   "deviator_min_kPa", "frequency_Hz")
    assert conditioned_keys("biaxial", [full, _test(frequency_Hz=5.0)]) == (
        "confining_pressure_kPa", "deviator_max_kPa", "frequency_Hz")
    box = dict(source="planted", rig="box", load_min_kN=10.0, load_max_kN=40.0)
    assert conditioned_keys("box", [box]) == ("cyclic_max_kN", "cyclic_min_kN", "settlement_force_kN")
    assert conditioned_keys("biaxial", []) == ()
