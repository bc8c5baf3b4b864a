"""The stone model switch (ballaststudy.stones) in the scenario: part of the key (the
bonded model keeps the keys it had), named in the case file, run through the one runner;
what a model cannot run is refused in one line before anything runs."""
import json
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
    split = {"splitting": True, **{k: v for k, v in cfg["rigid_stones"].items() if k != "splitting"}}
    with pytest.raises(ConfigError, match="c.yaml.*rigid_stones.splitting.*stone_model bonded's stones do not split"):
        check_stone_model({**cfg, "rigid_stones": split}, "c.yaml", stages=())
    assert check_stone_model({**cfg, "stone_model": "rigid", "rigid_stones": split,
                              "loop": {"effects": ["rate", "fatigue"]}}, "c.yaml",
                             stages=("loop.effects",)) == "rigid"
    with pytest.raises(ConfigError, match="loop.effects.*fatigue acts on the strengths of splitting stones"):
        check_stone_model({**cfg, "stone_model": "rigid", "loop": {"effects": ["fatigue"]}},
                          "c.yaml", stages=("loop.effects",))
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
    with pytest.raises(ValueError, match="bonded stone model's stones do not split"):
        scenario("biaxial", [asm], BiaxialParams(), 1, splitting=LAW)
    with pytest.raises(ValueError, match="modifier fatigue acts on splitting stones"):
        scenario("biaxial", [asm], BiaxialParams(), 1, [("fatigue", FATIGUE)], stone_model="rigid")


# weak stones that split in the first cycles of the small specimen; damage fast enough to
# matter within them (b = 2: a cycle at half the strength costs a quarter of it)
LAW = dict(sigma0=1e6, m=3.0, d0=0.04, fines_diameter=0.0, every=50)
FATIGUE = {"fatigue_exponent": 2.0, "endurance_ratio": 0.2}


def test_splitting_stones_with_fatigue_run_and_resume_bitwise_through_the_runner(setup, tmp_path):
    """The splitting law is part of the key (off: the key without it), the strengths come
    from the specimen's seed, the case file records the law; with the fatigue effect the
    stones gain damage at every cycle end, and a run killed after a checkpoint resumes
    bit for bit (the damage and the peaks are engine state)."""
    from ballaststudy.rig.biaxial import BiaxialParams
    from ballaststudy.rig.biaxial.output import CHANNEL_UNITS
    from ballaststudy.rig.records import cyclic_dataset
    from ballaststudy.scenario.runner import prepared_run
    from ballaststudy.scenario.scenario import scenario
    asm, config, _ = setup
    params = BiaxialParams.from_config(load_config(config)["rig"])
    plain = scenario("biaxial", [asm], params, 3, stone_model="rigid")
    split = scenario("biaxial", [asm], params, 3, stone_model="rigid", splitting=LAW)
    tired = scenario("biaxial", [asm], params, 3, [("fatigue", FATIGUE)], stone_model="rigid", splitting=LAW)
    assert plain.splitting is None and len({plain.key, split.key, tired.key}) == 3
    assert plain.key == scenario("biaxial", [asm], params, 3, stone_model="rigid", splitting=None).key

    full, _ = prepared_run(tired, 0, tmp_path / "full" / "case0.nc", checkpoint_every=1)
    full.run()
    sim = full.rig.sim
    assert sim.crushing_settings() == {"criterion": "largest_contact_force", "sigma0_Pa": [LAW["sigma0"]] * 2, "weibull_modulus": [LAW["m"]] * 2,
                                       "d0_m": LAW["d0"], "seed": full.rig.layout.seed % 2 ** 53,
                                       "fines_diameter_m": 0.0, "every_steps": LAW["every"]}
    assert len(sim.splits) > 0 and (sim.clumps.damage > 0).any() and (sim.clumps.damage < 1).all()
    first, _ = prepared_run(tired, 0, tmp_path / "crash" / "case0.nc", checkpoint_every=1)
    first.run(stop_after=2)
    first.advance(max_steps=300)        # progress after the checkpoint that the crash loses
    resumed, was = prepared_run(tired, 0, tmp_path / "crash" / "case0.nc", checkpoint_every=1)
    assert was
    resumed.run()
    a, b = (cyclic_dataset(r, CHANNEL_UNITS, "t") for r in (full, resumed))
    assert json.loads(a.attrs["stone_splitting_json"]) == sim.crushing_settings()
    assert a["broken_mass_share"].values[-1] > 0 and np.all(np.diff(a["broken_mass_share"].values) >= 0)
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    for name in ("damage", "peak", "strength", "pos"):
        assert np.array_equal(getattr(sim.clumps, name), getattr(resumed.rig.sim.clumps, name)), name
    # fatigue acts from the end of cycle 0 on (hook-only: it may share the plain cycle 0)
    fresh, _ = prepared_run(split, 0, tmp_path / "split" / "case0.nc")
    fresh.run(stop_after=1)
    end0 = full.cyc["cycle_end_step"][0]
    assert fresh.cyc["cycle_end_step"][0] == end0
    assert np.array_equal(fresh.rig.sim.split_log()["step"], sim.split_log()["step"][sim.split_log()["step"] <= end0])


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


def test_a_case_run_reads_the_splitting_law_from_the_config(setup, tmp_path, capsys):
    """case run with stone_model rigid and rigid_stones.splitting: the case file records
    the config's law (and the seed it drew from); with bonded stones the same section is
    refused in one line, exit 2, nothing written."""
    from ballaststudy.cli import main
    asm, config, folder = setup
    law = {"splitting": True, "criterion": "deviator", "strength_sigma0_Pa": [2.0e6, 3.0e5], "weibull_modulus": [4.0, 2.5],
           "reference_diameter_m": 0.05, "fines_diameter_m": 0.004, "check_every_steps": 70}
    out = tmp_path / "case.nc"
    rigid = _config(folder, stone_model="rigid", rigid_stones=law)
    assert main(["case", "run", str(asm), "--cycles", "1", "--quiet", "--out", str(out),
                 "--effect", "fatigue:fatigue_exponent=10,endurance_ratio=0.3", "--config", str(rigid)]) == 0
    prov = json.loads(Path(f"{out}.prov.json").read_text())
    assert prov["params"]["effects"] == [["fatigue", {"fatigue_exponent": 10.0, "endurance_ratio": 0.3}]]
    ds = open_netcdf(out, "metrics")
    recorded = json.loads(ds.attrs["stone_splitting_json"])
    assert recorded == {"criterion": "deviator", "sigma0_Pa": [2.0e6, 3.0e5], "weibull_modulus": [4.0, 2.5], "d0_m": 0.05, "seed": ds.attrs["seed"] % 2 ** 53,
                        "fines_diameter_m": 0.004, "every_steps": 70}
    refused = tmp_path / "refused.nc"
    capsys.readouterr()
    assert main(["case", "run", str(asm), "--cycles", "1", "--quiet", "--out", str(refused),
                 "--config", str(_config(folder, stone_model="bonded", rigid_stones=law))]) == 2
    assert not refused.exists() and not list(tmp_path.glob("refused*"))
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rigid_stones.splitting" in err[0] and "stone_model rigid" in err[0]
    unsplit = _config(folder, stone_model="rigid")
    for config, effect, why in ((unsplit, "fatigue:fatigue_exponent=10,endurance_ratio=0.3", "splitting"),
                                (rigid, "fatigue:fatigue_exponent=10", "fatigue_exponent=VALUE,endurance_ratio"),
                                (rigid, "fatigue:fatigue_exponent=0.1,endurance_ratio=0.3", "outside"),
                                (rigid, "abrasion:wear_per_cycle=0.1", "flat joints"),
                                (rigid, "glue:x=1", "not an effect")):
        assert main(["case", "run", str(asm), "--cycles", "1", "--quiet", "--out", str(refused),
                     "--effect", effect, "--config", str(config)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "--effect" in err[0] and why in err[0], err
    assert not refused.exists()
