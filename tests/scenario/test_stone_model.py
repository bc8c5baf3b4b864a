"""The stone model switch (ballaststudy.stones) in the scenario: part of the key (the
bonded model keeps the keys it had), named in the case file, run through the one runner;
what a model cannot run is refused in one line before anything runs."""
from pathlib import Path

import numpy as np
import pytest
import yaml

from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.config import load_config
from ballaststudy.inputs import open_netcdf
from ballaststudy.rig.biaxial import BiaxialRig
from ballaststudy.schema import ConfigError
from ballaststudy.scenario.scenario import check_stone_model

ROOT = Path(__file__).resolve().parents[2]


def _conditions(folder):
    path = Path(folder) / "stones.yaml"
    path.write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=30.0, deviator_min_kPa=10.0,
        deviator_max_kPa=50.0, frequency_Hz=20.0, curves=[dict(
            file="a.dat", quantity="axial_strain", units="1", sign="compression_positive")])))
    return path


def _config(folder, **keys):
    cfg = yaml.safe_load(Path(folder, "config.yaml").read_text())
    cfg.update(keys)
    path = Path(folder) / f"config_{'_'.join(f'{k}{v}' for k, v in keys.items()) or 'plain'}.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return path


def test_a_rigid_scenario_runs_its_own_case_beside_the_bonded_one(setup):
    """The same specimen under both models: two keys (the bonded one as without the
    switch), the rigid case file names its model, its stones are clumps that never break
    (breakage rate 0, as many fragments as stones), and both record every cycle."""
    asm, _, folder = setup
    test = _conditions(folder)
    runs = {}
    for model in ("bonded", "rigid"):
        config = _config(folder, stone_model=model)
        ev = Evaluator([], [asm], [(test, [1.0])], config, 2, "axial_strain", folder / "models")
        ev(np.zeros((1, 0)))
        runs[model] = (ev.scenarios({})[0], ev.sets[0]["cases"][0][0])
    plain = Evaluator([], [asm], [(test, [1.0])], folder / "config.yaml", 2, "axial_strain", folder / "m")
    assert plain.scenarios({})[0].key == runs["bonded"][0].key
    assert runs["rigid"][0].key != runs["bonded"][0].key
    rigid, bonded = (open_netcdf(runs[m][1], "metrics") for m in ("rigid", "bonded"))
    assert rigid.attrs["stone_model"] == "rigid" and bonded.attrs["stone_model"] == "bonded"
    assert rigid.sizes["cycle"] == bonded.sizes["cycle"] == 2
    assert np.all(rigid["breakage_rate"].values == 0.0)
    specimen = BiaxialRig.from_dataset(open_netcdf(asm, "assembled"), "engine_checkpoint")
    stones = int(specimen.fragments().max()) + 1        # what the assembly left
    assert np.all(rigid["n_fragments"].values == stones)
    assert np.all(np.isfinite(rigid["void_ratio"].values))


def test_what_the_rigid_model_cannot_run_is_refused_before_it_runs(tmp_path):
    cfg = load_config(ROOT / "config" / "config.yaml")
    assert check_stone_model(cfg, "c.yaml") == "bonded"
    rigid = {**cfg, "stone_model": "rigid", "calibration": {"parameters": {"mu": {}, "F_str_co": {}}}}
    with pytest.raises(ConfigError, match="calibration.parameters.*F_str_co acts on flat joints"):
        check_stone_model(rigid, "c.yaml")
    assert check_stone_model(rigid, "c.yaml", stages=()) == "rigid"      # case run: not its stage
    with pytest.raises(ConfigError, match="parametric.F_str_co"):
        check_stone_model(rigid, "c.yaml", stages=("parametric",))
    with pytest.raises(ConfigError, match="loop.effects.*abrasion"):
        check_stone_model({**cfg, "stone_model": "rigid", "loop": {"effects": ["rate", "abrasion"]}},
                          "c.yaml", stages=("loop.effects",))
    with pytest.raises(ConfigError, match="cal.yaml.*parameters.*F_str_co"):
        check_stone_model(cfg, "c.yaml", model="rigid", parameters=("cal.yaml", {"F_str_co": 2.0}),
                          stages=())
    with pytest.raises(ConfigError, match="backend.*cuda.*bonded stones only"):
        check_stone_model({**cfg, "backend": "cuda"}, "c.yaml", model="rigid", stages=())
    bad = tmp_path / "bad.yaml"
    raw = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    raw["databases_file"] = str(ROOT / raw["databases_file"])
    bad.write_text(yaml.safe_dump({**raw, "stone_model": "glued"}))
    with pytest.raises(ConfigError, match="stone_model"):
        load_config(bad)


def test_a_scenario_refuses_a_modifier_the_model_has_nothing_for(setup):
    from ballaststudy.scenario.scenario import scenario
    from ballaststudy.rig.biaxial import BiaxialParams
    asm, _, _ = setup
    with pytest.raises(ValueError, match="F_str_co acts on flat joints; the rigid stone model has none"):
        scenario("biaxial", [asm], BiaxialParams(), 1, [("F_str_co", {"F_str_co": 3.5})],
                 stone_model="rigid")
    with pytest.raises(ValueError, match="unknown stone model 'glued'"):
        scenario("biaxial", [asm], BiaxialParams(), 1, stone_model="glued")


def test_the_specimen_mass_of_the_driven_boundaries_counts_each_ball_once(setup):
    """The applied-force platen's mass is platen_mass_ratio x the specimen's inertial mass:
    the sum over the live balls (it was the first ball's mass times their number, an
    integer array taken as indices), and a rigid stone's clump counted once."""
    from ballaststudy.rig.biaxial import BiaxialParams, BiaxialRun
    asm, config, _ = setup
    runs = []
    for model in ("bonded", "rigid"):
        rig = BiaxialRig.from_dataset(open_netcdf(asm, "assembled"), "engine_checkpoint")
        rig.params = BiaxialParams.from_config(load_config(config)["rig"])
        rig.use_stone_model(model)
        runs.append(BiaxialRun(rig, 1))
    b = runs[0].rig.sim.balls
    live = b.alive == 1
    assert runs[0].specimen_mass() == pytest.approx((1.0 / b.minv[live]).sum(), rel=1e-12)
    assert runs[1].specimen_mass() == pytest.approx(b.mass[live].sum(), rel=1e-12)
