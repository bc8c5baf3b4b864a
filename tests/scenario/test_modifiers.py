"""The effect modifiers (scenario.modifiers, role "effect": the loop's candidates) on a small assembled biaxial specimen: each switches on
exactly the mechanism its docstring names and nothing else, so a fitted effect strength
means what the report says it means.

fouling        stone-stone friction times (1 - loss VCI / 100), walls untouched; no VCI: no change
end_restraint  stone-platen friction = the value, stone-stone and membrane untouched
membrane_friction  stone-membrane friction = the value, stone-stone and platens untouched
rate           real-time mode, no local damping, the stone dashpot; a cycle lasts 1/f in
               simulated time (20 and 40 Hz: ratio 2)
abrasion       the strong network (normal force above the stone-stone mean) recomputed here;
               its balls' joints, and only those, lose the share per call; over the
               runner's cycles once per cycle, and a run resumed from its checkpoint
               re-attaches the hook (same curve and same final joint strengths as an
               uninterrupted one, where a resume without the hook differs)
check          a value out of bounds or a missing / extra name is a ValueError naming the modifier
Tolerances are tight (1e-12 relative, 10 % on the cycle duration): a sign or a factor of
two in any formula fails them."""
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.config import load_config
from ballaststudy.inputs import open_netcdf
from ballaststudy.measured.importer import load_conditions
from ballaststudy.scenario import runner
from ballaststudy.scenario.modifiers import EFFECTS, MODIFIERS, covariate
from ballaststudy.scenario.modifiers.abrasion import strong_balls, wear
from ballaststudy.rig.biaxial import MEMBRANE, PLATEN, BiaxialParams, BiaxialRig, BiaxialRun


STONES = (0, 1)
MU, BETA = "mu", "beta_n"


def _conditions(folder, name="t", frequency_Hz=20.0, **extra):
    """A planted triaxial test's conditions YAML (p 30, q 10-50 kPa); its path."""
    path = Path(folder) / f"{name}.yaml"
    path.write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=30.0, deviator_min_kPa=10.0,
        deviator_max_kPa=50.0, frequency_Hz=frequency_Hz, curves=[dict(
            file="a.dat", quantity="axial_strain", units="1", sign="compression_positive")],
        **extra)))
    return path


def _rig(setup, conditions):
    """A fresh load of the specimen with the config's rig parameters and the conditions."""
    asm, config, _ = setup
    rig = BiaxialRig.from_dataset(open_netcdf(asm, "assembled"), "engine_checkpoint")
    rig.params = BiaxialParams.from_config(load_config(config)["rig"])
    rig.params.take_conditions(conditions)
    return rig


@pytest.mark.parametrize("vci", [25.0, None])
def test_fouling_scales_stone_stone_friction_by_vci(setup, vci):
    extra = {"covariates": {"VCI": {"value": vci, "units": "%"}}} if vci is not None else {}
    cond = load_conditions(_conditions(setup[2], f"fouling{vci}", **extra))
    rig = _rig(setup, cond)
    mu0 = rig.sim.contact_coefficient(MU)
    MODIFIERS["fouling"].apply(rig, {"friction_loss": 0.4}, cond.get("covariates"))
    mu = rig.sim.contact_coefficient(MU)
    expected = mu0.copy()
    expected[:2, :2] *= 1.0 - 0.4 * (vci or 0.0) / 100.0      # 0.9 at VCI 25 %
    assert mu0[0, 0] > 0
    np.testing.assert_allclose(mu, expected, rtol=1e-12, atol=0)
    for a in STONES:                                          # walls exactly as they were
        assert mu[a, PLATEN] == mu0[a, PLATEN] and mu[a, MEMBRANE] == mu0[a, MEMBRANE]
    if vci is None:
        assert np.array_equal(mu, mu0)


@pytest.mark.parametrize("name, parameter, wall, value", [
    ("end_restraint", "platen_friction", PLATEN, 0.25), ("membrane_friction", "membrane_friction", MEMBRANE, 0.35)])
def test_a_wall_friction_sets_that_stone_wall_friction_only(setup, name, parameter, wall, value):
    cond = load_conditions(_conditions(setup[2]))
    rig = _rig(setup, cond)
    mu0 = rig.sim.contact_coefficient(MU)
    assert not np.any(mu0[:2, wall] == value)
    MODIFIERS[name].apply(rig, {parameter: value}, cond.get("covariates"))
    mu = rig.sim.contact_coefficient(MU)
    expected = mu0.copy()
    expected[:2, wall] = expected[wall, :2] = value
    assert np.array_equal(mu, expected)


def test_rate_real_time_undamped_with_dashpot_and_cycles_last_one_period(setup):
    durations = {}
    for f in (20.0, 40.0):
        cond = load_conditions(_conditions(setup[2], f"rate{f:g}", frequency_Hz=f))
        rig = _rig(setup, cond)
        beta0 = rig.sim.contact_coefficient(BETA)
        MODIFIERS["rate"].apply(rig, {"contact_damping_ratio": 0.3}, cond.get("covariates"))
        assert rig.params.mode == "real_time" and rig.params.frequency_Hz == f
        assert np.all(rig.sim.balls.damp == 0.0)
        beta = rig.sim.contact_coefficient(BETA)
        stone = np.zeros(beta.shape, bool)
        stone[:2, :] = stone[:, :2] = True
        assert np.all(beta[stone] == 0.3) and np.array_equal(beta[~stone], beta0[~stone])
        run = BiaxialRun(rig, 3)
        ends = []
        run.hooks.append(lambda r, k: ends.append((k, r.rig.sim.time)))
        run.run()
        assert not run.s.failure and [k for k, _ in ends] == [0, 1, 2]
        durations[f] = np.diff([t for _, t in ends])
        print(f"rate {f:g} Hz: cycle durations {durations[f]} s")
        np.testing.assert_allclose(durations[f], 1.0 / f, rtol=0.1)
    assert durations[20.0].mean() / durations[40.0].mean() == pytest.approx(2.0, rel=0.1)


def test_abrasion_wears_the_strong_network_joints_only(setup):
    cond = load_conditions(_conditions(setup[2]))
    rig = _rig(setup, cond)
    BiaxialRun(rig, 1).run()                    # quasi-static: the stones carry forces
    i, j, fn = rig.ball_contacts()
    n, stone = rig.layout.n_stone_balls, rig.sim.balls.stone
    between = (i < n) & (j < n) & (stone[i] != stone[j])
    above = between & (fn > fn[between].mean())
    strong = set(i[above].tolist()) | set(j[above].tolist())
    assert strong and set(strong_balls(rig).tolist()) == strong
    bd = rig.sim.bonds
    touched = np.array([a in strong or b in strong for a, b in zip(bd.i, bd.j)])
    assert touched.any() and not touched.all()
    sigc0, coh0 = bd.sigc.copy(), bd.coh.copy()
    hit = wear(rig, 0.1)
    assert np.array_equal(np.sort(hit), np.nonzero(touched)[0])
    for calls in (1, 3):                        # no run between: the same balls each time
        for now, before in ((bd.sigc, sigc0), (bd.coh, coh0)):
            np.testing.assert_allclose(now[touched], 0.9 ** calls * before[touched],
                                       rtol=1e-12, atol=0)
            assert np.array_equal(now[~touched], before[~touched])
        for _ in range(2):
            wear(rig, 0.1)
    print(f"abrasion: {len(strong)} strong balls of {n}, {touched.sum()} of {len(bd.i)} joints worn")


def test_abrasion_over_cycles_and_resumed_through_the_runner(setup, monkeypatch):
    asm, config, folder = setup
    cond_path = _conditions(folder, "abrasion")
    base = {"F_str_co": 1.0}        # weaker joints: the wear breaks some, the curve feels it
    ev = Evaluator(["wear_per_cycle"], [asm], [(cond_path, [1.0, 2.0, 3.0])], config, 3,
                   "axial_strain", folder / "ev", effect="abrasion", base=base)
    (sc,) = ev.scenarios({"wear_per_cycle": 0.05})
    assert sc.perturbation_m_s == 0.0 and sc.cycles == 3
    assert sc.modifier_values() == [("F_str_co", base), ("abrasion", {"wear_per_cycle": 0.05})]

    records, real_hooks = [], runner._hooks             # joint strengths at every cycle end
    monkeypatch.setattr(runner, "_hooks", lambda s: real_hooks(s) + [
        lambda run, cycle: records.append((cycle, run.rig.sim.bonds.sigc.copy(),
                                           run.rig.sim.intact_bonds()))])
    full = runner.run_case(sc, 0, folder / "full" / "case0.nc")
    full_records, records[:] = list(records), []

    out2 = folder / "resumed" / "case0.nc"
    out2.parent.mkdir()
    ckpt = out2.with_name(out2.stem + ".checkpoint.npz")
    rig = BiaxialRig.from_dataset(open_netcdf(asm, "assembled"), "engine_checkpoint")
    rig.params = sc.rig
    MODIFIERS["F_str_co"].apply(rig, base)
    sigc0 = rig.sim.bonds.sigc.copy()
    MODIFIERS["abrasion"].apply(rig, {"wear_per_cycle": 0.05}, sc.covariates)
    run = BiaxialRun(rig, 3, checkpoint=ckpt, checkpoint_every=1, metrics=sc.metrics)
    run.hooks += MODIFIERS["abrasion"].hooks({"wear_per_cycle": 0.05})
    run.run(stop_after=1)
    assert run.s.cycle == 1 and ckpt.is_file()
    spare = folder / "spare.checkpoint.npz"
    shutil.copy(ckpt, spare)
    resumed = runner.run_case(sc, 0, out2)
    assert [c for c, *_ in full_records] == [0, 1, 2] and [c for c, *_ in records] == [1, 2]

    strain = [open_netcdf(p, "metrics")["axial_strain"].values for p in (full, resumed)]
    assert np.array_equal(strain[0], strain[1])
    assert np.array_equal(full_records[-1][1], records[-1][1])
    # The resume without hooks must end elsewhere, or the equalities above cannot tell a
    # lost hook. Compared on the joint strengths, not the curve: wear that breaks no joint
    # in cycles 1-2 leaves the curve as it is (measured so with some kernels' rounding).
    unhooked = BiaxialRun.from_checkpoint(spare, cycles=3).run()
    other = np.array([r["axial_strain"] for r in unhooked.s.rows])
    assert not np.array_equal(unhooked.rig.sim.bonds.sigc, records[-1][1])

    for cycle, sigc, intact in full_records:            # at most one wear per cycle
        ratio = sigc[intact] / sigc0[intact]
        assert ratio.min() < 1.0 and ratio.min() >= 0.95 ** (cycle + 1) - 1e-12
        assert ratio.max() <= 1.0 + 1e-12
    print(f"abrasion runner: strains {strain[0]}, without the hook on resume {other}; "
          f"min strength ratio per cycle {[float((s[m] / sigc0[m]).min()) for _, s, m in full_records]}, "
          f"joints worn at the end {int(np.sum(full_records[-1][1] < sigc0))} of {len(sigc0)}")


def test_a_quasi_static_case_is_one_run_whatever_the_tests_frequency(setup):
    """The scenario key leaves a quasi-static test's f out (BiaxialParams.inert_keys): two
    tests that differ only in f get one case file from one run (labelled by the first),
    and the second test's case run apart under its own label gives every variable of it
    bit for bit (the sinusoid's frequency included). Under the rate effect (real time) f
    acts: two keys (its cycles last 1/f: the rate test above)."""
    asm, config, folder = setup
    paths = [_conditions(folder, f"qs{f:g}", frequency_Hz=f) for f in (5.0, 60.0)]
    ev = Evaluator([], [asm], [(p, [1.0, 2.0]) for p in paths], config, 2, "axial_strain", folder / "qs")
    at = ev(np.zeros((1, 0)))[0]
    (files,) = [st["cases"] for st in ev.sets]
    assert files[0] == files[1] and len(list((folder / "qs" / "cases").glob("*/case0.nc"))) == 1
    assert np.array_equal(at[:, :2], at[:, 2:])
    shared = open_netcdf(files[0][0], "metrics")
    assert shared.attrs["measured_conditions_file"] == str(paths[0])
    apart = open_netcdf(runner.run_case(ev.scenarios({})[1], 0, folder / "qs60" / "case0.nc"), "metrics")
    assert apart.attrs["measured_conditions_file"] == str(paths[1]) and not apart.attrs["failed"]
    assert "loading_frequency" in apart and apart.sizes["cycle"] == 2
    for name, var in apart.data_vars.items():
        assert np.array_equal(var.values, shared[name].values, equal_nan=var.dtype.kind == "f"), name
    rate = Evaluator(["contact_damping_ratio"], [asm], [(p, [1.0]) for p in paths], config, 2, "axial_strain",
                     folder / "qs", effect="rate")
    assert len({s.key for s in rate.scenarios({"contact_damping_ratio": 0.3})}) == 2


@pytest.mark.parametrize("failure_axial_strain", [0.15, 5e-6])
def test_abrasion_starts_from_the_plain_runs_first_loading(setup, monkeypatch, tmp_path, failure_axial_strain):
    """Abrasion acts from cycle 0's end (a hook only): with the first loading shared, its
    cases start from the state the plain case kept there (they keep none), no first
    loading of their own, its hook called for cycle 0 there; every variable and the joint
    strengths at every cycle's end equal its run made apart, bit for bit - the plain
    case's too (its state saved on the way). At a failure strain of 5e-6 (the first
    loading reaches 2e-5) the specimen gives way in its first loading: the abrasion case
    is that failure, not a resumed loading."""
    asm, config, folder = setup
    cfg = yaml.safe_load(config.read_text())
    cfg["rig"]["biaxial"]["loading"]["failure_axial_strain"] = failure_axial_strain
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump(cfg))
    cond = [(_conditions(tmp_path, "wear"), [1.0, 2.0, 3.0])]
    base = {"F_str_co": 1.0}
    make = lambda share, **kw: Evaluator(kw.pop("names", []), [asm], cond, config, 3, "axial_strain",
                                         tmp_path / "s", base=base, share_first_loading=share, **kw)
    plain, worn = make(True), make(True, names=["wear_per_cycle"], effect="abrasion")
    plain(np.zeros((1, 0)))
    (sc,) = plain.scenarios({})
    assert runner.first_loaded(tmp_path / "s" / "cases", sc, 0).is_file()
    fresh, real_fresh, real_hooks, strengths = [], runner.fresh_run, runner._hooks, []
    monkeypatch.setattr(runner, "fresh_run", lambda *a, **kw: fresh.append(a[0]) or real_fresh(*a, **kw))
    monkeypatch.setattr(runner, "_hooks", lambda s: real_hooks(s) + [      # joint strengths at cycle ends
        lambda run, cycle: strengths.append((cycle, run.rig.sim.bonds.sigc.copy()))])
    worn(np.array([[0.05]]))
    assert fresh == []                                      # no first loading of its own
    shared_strengths, strengths[:] = list(strengths), []
    (wsc,) = worn.scenarios({"wear_per_cycle": 0.05})
    assert runner.without_hook_only(wsc).key == sc.key
    assert not runner.first_loaded(tmp_path / "s" / "cases", wsc, 0).exists()   # the plain model's only
    for shared, scenario in ((worn.sets[0]["cases"][0][0], wsc), (plain.sets[0]["cases"][0][0], sc)):
        apart = runner.run_case(scenario, 0, tmp_path / "apart" / scenario.key / "case0.nc")
        a, b = open_netcdf(shared, "metrics"), open_netcdf(apart, "metrics")
        assert a.attrs["failed"] == b.attrs["failed"] == int(failure_axial_strain < 0.01)
        assert a.sizes["cycle"] == (0 if a.attrs["failed"] else 3) and set(a.data_vars) == set(b.data_vars)
        for name, var in a.data_vars.items():
            assert np.array_equal(var.values, b[name].values, equal_nan=var.dtype.kind == "f"), name
    cycles = [] if a.attrs["failed"] else [0, 1, 2]
    assert [c for c, _ in shared_strengths] == cycles and [c for c, _ in strengths[:len(cycles)]] == cycles
    for (_, x), (_, y) in zip(shared_strengths, strengths):
        assert np.array_equal(x, y)
    if cycles:                                              # the wear acted from cycle 0 on
        assert np.all(shared_strengths[0][1] <= strengths[-1][1]) and np.any(shared_strengths[0][1] < strengths[-1][1])


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_check_rejects_bad_values_naming_the_modifier(name):
    effect = MODIFIERS[name]
    mid = {q.name: 0.5 * (q.low + q.high) for q in effect.parameters}
    effect.check({q.name: q.low for q in effect.parameters})
    effect.check({q.name: q.high for q in effect.parameters})
    bads = [{}, {**mid, "extra": 0.5}, {"other": 0.5}]
    for p in effect.parameters:
        bads += [{**mid, p.name: p.low - 0.01}, {**mid, p.name: p.high + 0.01}, {**mid, p.name: -p.high}]
        if len(effect.parameters) > 1:
            bads.append({k: v for k, v in mid.items() if k != p.name})
    for bad in bads:
        with pytest.raises(ValueError, match=f"modifier {name}"):
            effect.check(bad)
        with pytest.raises(ValueError, match=f"modifier {name}"):
            effect.apply(None, bad)                 # checked before the rig is touched
    assert len(effect.hooks(mid)) == (name in ("abrasion", "fatigue"))


@pytest.mark.parametrize("cov", [{"value": 150.0, "units": "%"}, {"value": 0.5, "units": "1"}])
def test_fouling_refuses_a_vci_it_cannot_read(cov):
    with pytest.raises(ValueError, match="covariate VCI"):
        covariate({"VCI": cov}, "VCI")


@pytest.mark.parametrize("load_control, failure_axial_strain",
                         [("applied_force", 0.15), ("servo", 0.15), ("applied_force", 5e-6)])
def test_a_real_time_tests_frequencies_share_one_cycle_0(setup, monkeypatch, tmp_path, load_control,
                                                          failure_axial_strain):
    """Under the rate effect (real time) f acts from the first trough on, not in cycle 0
    (BiaxialParams.first_cycle_inert_keys): two tests that differ only in f are two keys of
    one first_cycle_key; run_cases runs their cycle 0 once (one fresh run), each goes on
    from that state under its own f, and every variable equals its case run apart, bit for
    bit (under either load control; the servo's speed limit, set by f here, binds
    nowhere in these cycles: the test below checks it); the 40 Hz
    case's cycles last half the 20 Hz one's; no state is left. Where the
    specimen gives way in its first loading (failure strain 5e-6) the two cases are that
    failure."""
    asm, config, folder = setup
    cfg = yaml.safe_load(config.read_text())
    cfg["rig"]["biaxial"]["loading"].update(failure_axial_strain=failure_axial_strain, load_control=load_control,
                                            sine_velocity_min_m_s=1e-6)   # the servo's limit 2 pi f C dq
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump(cfg))
    cond = [(_conditions(tmp_path, f"rt{f}", frequency_Hz=f), [1.0, 2.0, 3.0]) for f in (20.0, 40.0)]
    ev = Evaluator(["contact_damping_ratio"], [asm], cond, config, 3, "axial_strain", tmp_path / "s", effect="rate")
    scenarios = ev.scenarios({"contact_damping_ratio": 0.3})
    assert scenarios[0].key != scenarios[1].key and scenarios[0].first_cycle_key == scenarios[1].first_cycle_key
    fresh, real_fresh = [], runner.fresh_run
    monkeypatch.setattr(runner, "fresh_run", lambda *a, **kw: fresh.append(a[0].key) or real_fresh(*a, **kw))
    ev(np.array([[0.3]]))
    assert len(fresh) == 1                                  # one cycle 0 for both
    assert not list((tmp_path / "s" / "cases").glob("*.first_cycle*"))     # nor its folder
    shared = [open_netcdf(ev.sets[0]["cases"][t][0], "metrics") for t in range(2)]
    for scenario, a in zip(scenarios, shared):
        b = open_netcdf(runner.run_case(scenario, 0, tmp_path / "apart" / scenario.key / "case0.nc"), "metrics")
        assert a.attrs["failed"] == b.attrs["failed"] == int(failure_axial_strain < 0.01)
        assert a.attrs["rig_params_json"] == b.attrs["rig_params_json"] and set(a.data_vars) == set(b.data_vars)
        for name, var in a.data_vars.items():
            assert np.array_equal(var.values, b[name].values, equal_nan=var.dtype.kind == "f"), name
    if not shared[0].attrs["failed"]:
        assert shared[0].sizes["cycle"] == 3
        ratio = shared[0]["cycle_steps"].values[1:] / shared[1]["cycle_steps"].values[1:]
        assert np.all(np.abs(ratio - 2.0) < 0.2), ratio


def test_continue_under_sets_what_the_first_trough_set_from_f(setup, tmp_path):
    """A state at the end of cycle 0 made at 40 Hz, gone on under 20 Hz
    (BiaxialRun.continue_under), equals the 20 Hz run stopped there in everything: engine,
    every controller's settings (the sinusoid's frequency, its servo's speed limit 2 pi f C
    dq: not binding in the short run above, so checked here), run state, parameters."""
    asm, config, folder = setup
    cfg = yaml.safe_load(config.read_text())
    cfg["rig"]["biaxial"]["loading"].update(load_control="servo", sine_velocity_min_m_s=1e-6)
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump(cfg))
    cond = [(_conditions(tmp_path, f"rt{f}", frequency_Hz=f), [1.0]) for f in (20.0, 40.0)]
    ev = Evaluator(["contact_damping_ratio"], [asm], cond, config, 2, "axial_strain", tmp_path / "s", effect="rate")
    at20, at40 = ev.scenarios({"contact_damping_ratio": 0.3})
    runner.run_first_cycle(at40, 0, tmp_path / "40.npz")
    runner.run_first_cycle(at20, 0, tmp_path / "20.npz")
    gone_on = runner._from_first_cycle(at20, 0, tmp_path / "out" / "case0.nc", tmp_path / "40.npz")
    own = BiaxialRun.from_checkpoint(tmp_path / "20.npz", cycles=2)
    as_made = BiaxialRun.from_checkpoint(tmp_path / "40.npz", cycles=2)
    assert gone_on.s.cycle == 1 and gone_on.rig.params == own.rig.params != as_made.rig.params
    assert gone_on.rig.engine_bytes() == own.rig.engine_bytes() and gone_on.s == own.s
    mine, theirs, before = gone_on.control.to_dict(), own.control.to_dict(), as_made.control.to_dict()
    assert mine.keys() == theirs.keys()
    for name in mine:
        assert np.array_equal(mine[name], theirs[name]), name
    assert any(not np.array_equal(before[name], theirs[name]) for name in mine)   # 40 Hz's differ
