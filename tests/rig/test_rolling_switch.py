"""Rolling resistance in the rigs' law (rig.<kind>.assembly.rolling_resistance): off by
default (the law of every earlier run), on with epsd and the rolling_* coefficients for
every contact; the mu_r modifier sets the stone-stone rolling friction only, and refuses
a specimen assembled without rolling resistance; a rolling_* key that would do nothing and
a calibration of mu_r on such specimens are refused in one line (file, key, what is
allowed). That mu_r = 0 is the law without rolling: tests/dem/test_rolling.py."""
import numpy as np
import pytest

from ballaststudy.cli import main
from ballaststudy.dem.law import ContactLaw
from ballaststudy.dem.materials import STONE_MATERIALS
from ballaststudy.rig.biaxial import MEMBRANE, PLATEN, BiaxialLayout, BiaxialParams, BiaxialRig
from ballaststudy.rig.deposition import new_simulation
from ballaststudy.rig.library import load_library
from ballaststudy.scenario.modifiers import MODIFIERS, ModifierError
from ..shipped import shipped_config

DOMAIN = (-1.0, -1.0, 1.0, 1.0)


def _rig(lib, **params):
    p = BiaxialParams(**params)
    return BiaxialRig(new_simulation(lib, p, DOMAIN, 0.0), BiaxialLayout(), p)


def test_default_law_is_the_one_without_rolling(small_library):
    rig = _rig(load_library(small_library))
    assert rig.sim.law.names == ContactLaw.pfc().names
    assert rig.sim.law.layout() == ContactLaw.pfc().layout()


def test_epsd_sets_the_rolling_coefficients_of_every_contact(small_library):
    rig = _rig(load_library(small_library), rolling_resistance="epsd", rolling_friction=0.2,
               rolling_stiffness_ratio=0.5, rolling_damping_ratio=0.1)
    sim = rig.sim
    sim._ensure_materials(MEMBRANE + 1)          # the walls' rows, as add_wall makes them
    assert sim.law.names[-1] == "epsd"
    for name, value in (("mu_r", 0.2), ("kr_ratio", 0.5), ("eta_r", 0.1)):
        assert np.all(sim.contact_coefficient(name) == value), name


def test_mu_r_modifier_sets_stone_stone_only(small_library):
    rig = _rig(load_library(small_library), rolling_resistance="epsd", rolling_friction=0.05)
    rig.sim._ensure_materials(MEMBRANE + 1)
    MODIFIERS["mu_r"].apply(rig, {"mu_r": 0.3})
    table = rig.sim.contact_coefficient("mu_r")
    for a in STONE_MATERIALS:
        for b in STONE_MATERIALS:
            assert table[a, b] == 0.3
        assert table[a, PLATEN] == table[a, MEMBRANE] == 0.05
    assert MODIFIERS["mu_r"].current(rig) == {"mu_r": 0.3}


def test_mu_r_modifier_refuses_a_specimen_without_rolling(small_library):
    rig = _rig(load_library(small_library))
    with pytest.raises(ModifierError, match="rig.biaxial.assembly.rolling_resistance epsd"):
        MODIFIERS["mu_r"].apply(rig, {"mu_r": 0.3})


@pytest.mark.parametrize("rig, key", [("biaxial", "rolling_friction"), ("box", "rolling_damping_ratio")])
def test_a_rolling_key_without_rolling_is_one_line(tmp_path, capsys, rig, key):
    path = shipped_config(tmp_path / "config.yaml", lambda cfg: cfg["rig"][rig]["assembly"].update({key: 0.1}))
    assert main(["config", "check", "--config", str(path)]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and f"{path}: rig.{rig}.assembly.{key}" in line, line
    assert "allowed: rolling_resistance epsd" in line, line
    shipped_config(path, lambda cfg: cfg["rig"][rig]["assembly"].update({key: 0.1, "rolling_resistance": "epsd"}))
    assert main(["config", "check", "--config", str(path)]) == 0
