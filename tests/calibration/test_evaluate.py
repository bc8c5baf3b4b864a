"""The calibration's model side: the material modifiers applied to an assembled specimen
exactly as named (bond strengths scaled by F_str_co / 3.5, the stone-stone friction set,
walls kept), a failed case's curve censored at the failure strain, curves compared in ln N
at the measured points, the scenarios an Evaluator builds and their cache keys (the
specimens' content, not their names)."""
import shutil
import json

import numpy as np
import pytest
import xarray as xr

from ballaststudy.calibration.evaluate import Evaluator
from ballaststudy.config import ConfigError
from ballaststudy.scenario.modifiers import MODIFIERS, material_modifiers
from ballaststudy.scenario.results import at_points, case_curve
from ballaststudy.scenario.scenario import conditioned_rig, scenario
from ballaststudy.rig.biaxial import MEMBRANE, PLATEN, BiaxialParams, BiaxialRig, assemble_biaxial
from ballaststudy.rig.library import load_library


def test_parameters_applied_as_named(specimen):
    rig = BiaxialRig.load(specimen)
    sim = rig.sim
    sigc, coh = sim.bonds.sigc.copy(), sim.bonds.coh.copy()
    mu0 = sim.contact_coefficient("mu")
    assert MODIFIERS["F_str_co"].current(rig) == {"F_str_co": 3.5}
    assert MODIFIERS["mu"].current(rig) == {"mu": mu0[0, 0]}
    for name, values in material_modifiers({"F_str_co": 7.0, "mu": 0.4}):
        MODIFIERS[name].apply(rig, values)
    np.testing.assert_allclose(sim.bonds.sigc, 2.0 * sigc, rtol=1e-15)
    np.testing.assert_allclose(sim.bonds.coh, 2.0 * coh, rtol=1e-15)
    mu = sim.contact_coefficient("mu")
    assert np.all(mu[:2, :2] == 0.4)
    for wall in (PLATEN, MEMBRANE):               # the rig's wall frictions kept
        assert np.all(mu[:2, wall] == mu0[:2, wall]) and np.all(mu[wall, :2] == mu0[wall, :2])


@pytest.mark.parametrize("name, column, value", [("E_star", "E", 1.0e9), ("kappa_star", "kappa", 1.5)])
def test_optional_contact_parameters(specimen, name, column, value):
    """E* and kappa* set the stone-stone contact's column exactly; walls keep theirs."""
    rig = BiaxialRig.load(specimen)
    before = rig.sim.contact_coefficient(column)
    assert MODIFIERS[name].current(rig) == {name: before[0, 0]}
    MODIFIERS[name].apply(rig, {name: value})
    after = rig.sim.contact_coefficient(column)
    assert np.all(after[:2, :2] == value) and np.all(after[:2, 2:] == before[:2, 2:])


def _metrics(path, rows, failed, failure_strain=0.15):
    ds = xr.Dataset({"axial_strain": ("cycle", np.asarray(rows, float))},
                    coords={"cycle": np.arange(len(rows))},
                    attrs={"failed": int(failed), "rig_params_json": json.dumps({"failure_axial_strain": failure_strain})})
    ds.to_netcdf(path)
    return path


def test_failed_case_censored_at_the_failure_strain(tmp_path):
    curve, failed = case_curve(_metrics(tmp_path / "a.nc", [0.01, 0.02], True), "axial_strain", 5)
    assert failed and curve.tolist() == [0.01, 0.02, 0.15, 0.15, 0.15]
    curve, _ = case_curve(_metrics(tmp_path / "b.nc", [], True), "axial_strain", 3)
    assert curve.tolist() == [0.15] * 3                      # failed in its first loading
    curve, _ = case_curve(_metrics(tmp_path / "c.nc", [0.2], True), "axial_strain", 2)
    assert curve.tolist() == [0.2, 0.2]                      # past the failure strain: its last
    curve, failed = case_curve(_metrics(tmp_path / "d.nc", [0.01, 0.02, 0.03], False), "axial_strain", 3)
    assert not failed and curve.tolist() == [0.01, 0.02, 0.03]
    with pytest.raises(ValueError, match="not failed"):
        case_curve(_metrics(tmp_path / "e.nc", [0.01], False), "axial_strain", 3)


def test_curve_at_measured_points_in_ln_n():
    n = np.arange(1, 11, dtype=float)
    curve = 0.01 + 0.003 * np.log(n)               # linear in ln N: exact at any N in between
    pts = np.array([1.0, 2.5, 4.96, 10.0])
    np.testing.assert_allclose(at_points(curve, pts), 0.01 + 0.003 * np.log(pts), rtol=1e-12)


def _key(specimen, values, cycles=5, conditions=None):
    rig, _ = conditioned_rig("biaxial", {}, conditions)
    return scenario("biaxial", [specimen], rig, cycles, material_modifiers(values), conditions).key


def test_scenario_key_changes_with_what_decides_the_cases(specimen):
    key = _key(specimen, {"mu": 0.7, "F_str_co": 3.5})
    assert key == _key(specimen, {"mu": 0.7 + 1e-15, "F_str_co": 3.5})     # round-off
    assert key != _key(specimen, {"F_str_co": 3.5, "mu": 0.7})             # the order they are applied in
    assert key != _key(specimen, {"mu": 0.71, "F_str_co": 3.5})
    assert key != _key(specimen, {"mu": 0.7, "F_str_co": 3.5}, cycles=6)


def test_scenario_key_leaves_out_what_does_not_act(specimen):
    """A quasi-static test's f and a covariate no modifier reads decide nothing: scenarios
    that differ only in them are one key (one run); the rate effect's real time reads f,
    fouling reads VCI, and a config in real time reads f: other keys."""
    def key(f=5.0, vci=None, modifiers=(), mode=None):
        cond = {"rig": "triaxial", "confining_pressure_kPa": 60.0, "deviator_min_kPa": 15.0,
                "deviator_max_kPa": 230.0, "frequency_Hz": f,
                "covariates": {"VCI": {"value": vci, "units": "%"}} if vci is not None else {}}
        rig, _ = conditioned_rig("biaxial", {}, cond, mode=mode)
        return scenario("biaxial", [specimen], rig, 3, list(modifiers), cond).key

    rate = [("rate", {"contact_damping_ratio": 0.3})]
    fouling = [("fouling", {"friction_loss": 0.5})]
    abrasion = [("abrasion", {"wear_per_cycle": 0.01})]
    assert key(5.0) == key(60.0) and key(5.0, abrasion) == key(60.0, abrasion)
    assert key(5.0, modifiers=rate) != key(60.0, modifiers=rate) != key(60.0)
    assert key(5.0, mode="real_time") != key(60.0, mode="real_time") != key(60.0)
    assert key(5.0, mode="real_time") != key(5.0, modifiers=rate)        # the dashpot
    assert key(5.0, vci=20.0) == key(5.0, vci=60.0) == key(5.0)
    assert key(5.0, 20.0, fouling) != key(5.0, 60.0, fouling) == key(60.0, 60.0, fouling)
    assert key(5.0, 60.0, fouling) != key(5.0, None, fouling)


def test_scenario_key_sees_the_specimens_content_not_their_names(specimen, small_library, tmp_path):
    """The same specimen under another name: the same cases; another specimen under the
    first one's name (re-assembled from another seed): other cases."""
    copy = tmp_path / "renamed.nc"
    shutil.copy(specimen, copy)
    assert _key(copy, {"mu": 0.7}) == _key(specimen, {"mu": 0.7})
    p = BiaxialParams(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
                      fill_area_ratio=0.9)
    assemble_biaxial(load_library(small_library), p, seed=8).save(copy)       # same name, new content
    assert _key(copy, {"mu": 0.7}) != _key(specimen, {"mu": 0.7})


def test_a_modifier_outside_its_bounds_is_refused(specimen):
    with pytest.raises(ValueError, match="mu = -0.1 outside"):
        _key(specimen, {"mu": -0.1})
    with pytest.raises(ValueError, match="F_str_co = 0 outside"):           # open at 0
        _key(specimen, {"F_str_co": 0.0})


def test_a_covariate_edited_changes_the_cache_key(specimen, tmp_path, fast_config, planted_conditions):
    """An effect may act through a declared covariate (fouling through VCI): the same p, q
    and f at another VCI is another set of cases, not a cached one."""
    config = fast_config(tmp_path)
    keys = []
    for vci in (20.0, 60.0, 60.0):
        c = planted_conditions(tmp_path / f"v{len(keys)}.yaml", 50.0,
                               covariates={"VCI": {"value": vci, "units": "%"}})
        ev = Evaluator(["friction_loss"], [specimen], [(c, np.array([1.0]))], config, 2, "axial_strain",
                       tmp_path / "cal", effect="fouling")
        keys.append(ev.scenarios({"friction_loss": 0.5})[0].key)
    assert keys[0] != keys[1] and keys[1] == keys[2]


def test_the_plain_model_runs_at_the_fixed_parameters(specimen, tmp_path, fast_config, planted_conditions):
    """The loop's plain model (no effect, nothing varied) and its candidates (an effect on
    top) both run at the fixed material parameters (e.g. calibrated ones)."""
    config, c = fast_config(tmp_path), planted_conditions(tmp_path / "t.yaml", 50.0)
    base = {"F_str_co": 1.0}
    plain = Evaluator([], [specimen], [(c, np.array([1.0]))], config, 2, "axial_strain", tmp_path, base=base)
    rate = Evaluator(["contact_damping_ratio"], [specimen], [(c, np.array([1.0]))], config, 2, "axial_strain",
                     tmp_path, effect="rate", base=base)
    assert plain.scenarios({})[0].modifier_values() == [("F_str_co", base)]
    applied = rate.scenarios({"contact_damping_ratio": 0.3})[0].modifier_values()
    assert applied == [("F_str_co", base), ("rate", {"contact_damping_ratio": 0.3})]   # material first


def test_config_error_crosses_process_boundaries():
    """A worker's bad-input error reaches the parent as the same one line."""
    import pickle

    err = pickle.loads(pickle.dumps(ConfigError("a.yaml", "k", "bad")))
    assert isinstance(err, ConfigError) and str(err) == "a.yaml: k: bad" and err.key == "k"


def test_an_interrupted_calibration_reuses_finished_cases(specimen, tmp_path, fast_config, planted_conditions):
    """A set evaluated again (a rerun after an interruption) reads its finished cases and
    runs nothing: same curves, files untouched."""
    config = fast_config(tmp_path)
    conditions = planted_conditions(tmp_path / "t.yaml", 60.0)
    theta = np.array([[3.0, 0.6]])

    def evaluator():
        return Evaluator(["F_str_co", "mu"], [specimen], [(conditions, np.array([1.0, 2.0]))], config, 2,
                         "axial_strain", tmp_path / "cal")
    first = evaluator()(theta)
    files = sorted((tmp_path / "cal" / "cases").rglob("*"))
    stamps = [f.stat().st_mtime_ns for f in files]
    again = evaluator()
    second = again(theta)
    assert np.array_equal(first[0], second[0]) and len(again.sets) == 1
    assert sorted((tmp_path / "cal" / "cases").rglob("*")) == files
    assert [f.stat().st_mtime_ns for f in files] == stamps



def test_several_targets_make_one_curve(specimen, tmp_path, fast_config, planted_conditions):
    """Two target tests (different q): each set runs the specimens under each; the points
    come one test after the other, each test's from its own cases."""
    config = fast_config(tmp_path)
    tests = []
    for q, pts in ((40.0, [1.0, 2.0]), (80.0, [1.5])):
        c = planted_conditions(tmp_path / f"q{q:g}.yaml", q)
        tests.append((c, np.array(pts)))
    ev = Evaluator(["mu"], [specimen], tests, config, 2, "axial_strain", tmp_path / "cal")
    out = ev(np.array([[0.7]]))[0]
    curves = ev.sets[0]["curves"]
    assert out.shape == (1, 3) and curves.shape == (1 + 1, 1, 2)
    np.testing.assert_allclose(out[0, :2], curves[0, 0])            # test 0 at N = 1, 2
    np.testing.assert_allclose(out[0, 2], at_points(curves[1, 0], np.array([1.5]))[0])
    assert curves[1, 0, -1] > curves[0, 0, -1]                      # the larger q strains more
    rigs = [json.loads(xr.open_dataset(per_test[0]).attrs["rig_params_json"])["deviator_max_kPa"]
            for per_test in ev.sets[0]["cases"]]                         # one scenario per test
    assert rigs == [40.0, 80.0]


def test_the_chaos_probe_is_a_set_of_its_own(specimen, tmp_path, fast_config, planted_conditions):
    """The plain set run again from velocities perturbed by 1e-9 m/s (loop.select's chaos
    probe): its own cache key (none in the plain set's context: its cached cases stay valid),
    each case seeded by its index; the curve moves, but by chaos, not by a new specimen.
    Another probe (perturbation_seed 1) is a set of its own again, its direction another."""
    config, c = fast_config(tmp_path), planted_conditions(tmp_path / "t.yaml", 50.0)
    make = lambda **kw: Evaluator([], [specimen], [(c, np.array([1.0, 2.0]))], config, 2, "axial_strain",
                                  tmp_path / "cal", **kw)
    plain, probe = make(), make(perturbation_m_s=1e-9)
    plain_sc, probe_sc = plain.scenarios({})[0], probe.scenarios({})[0]
    assert plain_sc.perturbation_m_s == 0.0 and probe_sc.perturbation_seed == 0
    key, probe_key = plain_sc.key, probe_sc.key
    assert probe_key != key
    a, b = plain(np.zeros((1, 0)))[0], probe(np.zeros((1, 0)))[0]
    assert not np.array_equal(a, b) and np.all(np.abs(a - b) < 0.5 * np.abs(a))
    other = make(perturbation_m_s=1e-9, perturbation_seed=1)
    other_key = other.scenarios({})[0].key
    assert other.scenarios({})[0].perturbation_seed == 1
    assert other_key not in (key, probe_key) and not np.array_equal(other(np.zeros((1, 0)))[0], b)
