"""`ballaststudy loop` end to end at tiny scale (three planted tests, one cheap candidate:
the outputs, the two horizons apart, nothing chosen with three tests - the rule cannot pass
with fewer than six), and bad input in one line before any case runs (CLI and Snakefile)."""
import json
import os
import shutil
import subprocess
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ballaststudy.cli import main
from ballaststudy.config import load_config
from ballaststudy.rig.kinds import params_from_config

from ..biaxial_fast import FAST_LOADING
from ..netcdf_documented import assert_documented
from ..shipped import shipped_config

ROOT = Path(__file__).resolve().parents[2]


def _config(folder, **loop):
    def change(cfg):
        cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING)
        cfg["loop"].update(dict(cases=2, cycles=5, design_sets=2, refine_rounds=1, refine_sets=2,
                                effects=["end_restraint", "fouling"], measurement_sd=1e-4,
                                posterior_samples=256), **loop)
    return shipped_config(Path(folder) / "config.yaml", change)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory, small_library):
    """(folder, config, [measured nc], [conditions], [specimens]): three planted tests,
    their curves a log law past the simulated cycles (the long-term horizon)."""
    from ballaststudy.measured.importer import import_test
    d = tmp_path_factory.mktemp("loop")
    config = _config(d)
    specimens = [d / f"s{k}.nc" for k in range(2)]
    for k, s in enumerate(specimens):
        assert main(["case", "assemble", str(small_library), "--case", str(k), "--rig", "biaxial",
                     "--width-m", "0.12", "--height-m", "0.24", "--config", str(config), "--out", str(s),
                     "--quiet"]) == 0
    measured, conditions = [], []
    for j, (p, f) in enumerate([(30, 5), (30, 40), (40, 20)]):
        conditions.append(d / f"t{j}.yaml")
        conditions[-1].write_text(yaml.safe_dump(dict(
            source="planted", rig="triaxial", confining_pressure_kPa=p, deviator_min_kPa=10.0,
            deviator_max_kPa=50.0, frequency_Hz=f,
            curves=[dict(file=f"t{j}.dat", quantity="axial_strain", units="1", sign="compression_positive")])))
        n = np.array([1.0, 1.7, 2.5, 3.9, 4.6, 30.0, 500.0])
        (d / f"t{j}.dat").write_text("".join(f"{a}, {0.001 + 0.0005 * np.log(a)}\n" for a in n))
        measured.append(d / f"t{j}.nc")
        import_test(conditions[-1], measured[-1])
    return d, config, measured, conditions, specimens


def _argv(tiny, out, config=None):
    d, cfg, measured, conditions, specimens = tiny
    return ["loop", *map(str, measured), "--conditions", *map(str, conditions), "--specimens",
            *map(str, specimens), "--out-dir", str(out), "--config", str(config or cfg), "--quiet"]


@pytest.fixture(scope="module")
def loop_run(tiny, tmp_path_factory):
    """(out folder, horizon law, loop.nc as written) of the loop on the tiny tests with the
    horizon table of their curves (test_loop_end_to_end runs it again in the folder)."""
    d = tmp_path_factory.mktemp("loop_run")
    out, horizon = d / "loop", d / "horizon"
    assert main(["horizon", *map(str, tiny[2]), "--out-dir", str(horizon), "--fit-cycles", "5", "--quiet"]) == 0
    with xr.open_dataset(horizon / "horizon.nc") as ds:
        law = str(ds["chosen_law"].values[0])
    assert main(_argv(tiny, out) + ["--jobs", "2", "--horizon", str(horizon / "horizon.nc")]) == 0
    return out, law, shutil.copy(out / "loop.nc", d / "loop.nc")


def test_loop_end_to_end(tiny, loop_run):
    out, law, _ = loop_run
    assert law in ("log", "hardening_log")              # the planted log law (hardening_log nests it)
    text = (out / "report.md").read_text()
    assert "## DEM horizon" in text and "## Long-term horizon (extrapolated, reported apart)" in text
    assert f"fitted by the **{law}** law, the law that carried 3 measured curves best from N <= 5" in text
    assert "| fouling | - |" in text and "not testable: no target declares VCI" in text
    assert "**No effect chosen**" in text
    assert yaml.safe_load((out / "chosen.yaml").read_text())["effect"] == "none"
    assert yaml.safe_load((out / "chosen.yaml").read_text())["stress_mapping"] == "none"
    assert "Stress mapping: **none**" in text
    with xr.open_dataset(out / "loop.nc") as ds:
        assert ds["plain"].shape == (3, 2, 5) and ds["candidate"].shape == (1, 4, 3, 2, 5)
        assert np.array_equal(ds["plain"].values[0], ds["plain"].values[1])      # t0, t1: one run
        refined = ds["candidate_value"].values[0, 2:, 0]       # the grid's 2 sets, then 1 round of 2
        assert np.all((refined > 0.0) & (refined < 1.2)) and refined[0] < refined[1]
        assert ds["measured"].size == 15                  # 5 points per test within N <= 5
        assert list(ds["effect"].values) == ["end_restraint"] and ds.attrs["untestable_effects"] == "fouling"
        assert ds["plain"].attrs["units"] == "1" and ds.attrs["Conventions"] == "CF-1.8"
        assert ds.attrs["stress_mapping"] == "none" and len(json.loads(ds.attrs["stress_mapping_json"])) == 3
        assert ds.attrs["likelihood"] == "multivariate t with dof = 1"       # K - 1, K = 2 specimens
        cands = json.loads(ds.attrs["candidates_json"])
        tests = json.loads(ds.attrs["tests_json"])
    assert all(np.isfinite(t["mean_coordination"]) and t["mean_coordination"] > 1 for t in tests)
    assert "| bias | mean_coordination |" in text
    assert cands[0]["tests"] == 3 and 0.0 <= cands[0]["mean"][0] <= 1.2
    assert (out / "curves.png").is_file() and (out / "report.md.prov.json").is_file()
    cached = sorted((out / "cases").rglob("*.nc"))
    # K x runs x (plain + 2 design + 2 refined sets): t0 and t1 differ in f only, one run
    # quasi-static (the scenario key leaves f out), so 2 runs for the 3 tests
    assert len(cached) == 2 * 2 * (1 + 2 + 2)
    assert not list((out / "cases").rglob("*.first_loaded.npz"))     # no hook-only candidate: none kept
    assert "at 2 parameter sets each + 1 x 2 refined around the held-out posteriors" in text
    stamp = [p.stat().st_mtime_ns for p in cached]
    assert main(_argv(tiny, out)) == 0                   # again: every case reused (no law: nothing extrapolated)
    assert "No accumulation law given" in (out / "report.md").read_text()
    assert [p.stat().st_mtime_ns for p in cached] == stamp


def test_documented_netcdf_loop(loop_run):
    assert_documented(loop_run[2], "loop")


@pytest.mark.parametrize("change, key", [
    (dict(cases=3), "loop.cases: 3 but 2 specimens given"),
    (dict(cycles=2), "loop.cycles"),
    (dict(quantity="volumetric_strain"), "the test has no volumetric_strain curve"),
])
def test_loop_checks_before_any_case(tiny, tmp_path, capsys, change, key):
    config = _config(tmp_path, **change)
    out = tmp_path / "out"
    assert main(_argv(tiny, out, config)) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and key in line, line
    assert not out.exists() or not any(out.rglob("*.nc"))


def test_a_stress_mapping_without_its_envelope_is_refused(tiny, tmp_path, capsys):
    """stress_mapping strength_ratio needs the specimens' strength envelope: one line naming
    the option, exit 2, before any case (the lab envelope is planted)."""
    config = _config(tmp_path)
    cfg = yaml.safe_load(config.read_text())
    cfg["stress_mapping"] = {"kind": "strength_ratio", "lab_envelope": {
        "citation": "planted", "confining_pressure_kPa": [10.0], "peak_deviator_kPa": [300.0]}}
    config.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    assert main(_argv(tiny, out, config)) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "--strength-envelope: missing" in line, line
    assert not out.exists() or not any(out.rglob("*.nc"))


def test_a_horizon_table_of_another_quantity_is_refused(tiny, tmp_path, capsys):
    from ballaststudy.loop.horizon import horizon_table
    n = np.geomspace(1.0, 1e4, 20)
    table = tmp_path / "horizon.nc"
    horizon_table({"t": (n, 0.001 * np.log(n))}, [100.0], quantity="volumetric_strain").to_netcdf(table)
    out = tmp_path / "out"
    assert main(_argv(tiny, out) + ["--horizon", str(table)]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "quantity: 'volumetric_strain'; allowed: the loop's 'axial_strain'" in line, line
    assert not out.exists() or not any(out.rglob("*.nc"))


def test_the_cuda_backend_is_refused_without_a_gpu(tmp_path):
    """--backend cuda where numba sees no CUDA GPU: one line naming the option, exit 2,
    before anything is read or written (numba's CUDA simulator, which the GPU tests
    switch on, is off in this process)."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    probe = subprocess.run([sys.executable, "-c", "from numba import cuda; print(cuda.is_available())"],
                           env=env, capture_output=True, text=True)
    if probe.stdout.strip() == "True":
        pytest.skip("this machine has a CUDA GPU")
    out = tmp_path / "out"
    for command in ("loop", "calibrate"):
        r = subprocess.run([sys.executable, "-c", "import sys; from ballaststudy.cli import main; "
                            "sys.exit(main(sys.argv[1:]))", command, "m.nc", "--conditions", "c.yaml",
                            "--specimens", "s.nc", "--out-dir", str(out), "--backend", "cuda"],
                           env=env, capture_output=True, text=True, cwd=tmp_path)
        assert r.returncode == 2 and "\n" not in r.stderr.strip(), r.stderr
        assert "--backend: cuda: numba sees no CUDA GPU" in r.stderr
    assert not out.exists()


def _workflow(tmp_path, data_dir, change, *options):
    for part in ("workflow", "config"):
        src = ROOT / part
        (shutil.copytree(src, tmp_path / part) if src.is_dir() else shutil.copy(src, tmp_path))
    path = tmp_path / "config" / "config.yaml"
    cfg = yaml.safe_load(path.read_text())
    cfg["measured"]["data_dir"] = str(data_dir)
    change(cfg["loop"])
    path.write_text(yaml.safe_dump(cfg))
    return subprocess.run(["snakemake", "--cores", "1", "-n", "-p", "loop", *options], cwd=tmp_path,
                          capture_output=True, text=True)


def test_snakefile_plans_the_loop(tmp_path, measured_data_dir):
    out = _workflow(tmp_path, measured_data_dir, lambda c: None)
    assert out.returncode == 0, out.stderr
    assert "rule specimen_assemble:" in out.stdout and "ballaststudy loop results/measured/" in out.stdout
    assert "ballaststudy horizon results/measured/" in out.stdout and "--fit-cycles 1000 10000" in out.stdout
    assert "--horizon results/horizon/horizon.nc" in out.stdout


def test_the_scale_config_plans_the_loop_on_full_size_specimens(tmp_path, measured_data_dir):
    """config/loop_scale.yaml (issue 34): config.yaml's loop to N = 2000 in real time on six
    0.30 x 0.60 m specimens, with the p = 30 kPa test the default leaves out; read alone (as
    the stages' command lines read it) it differs from config.yaml in those keys only."""
    out = _workflow(tmp_path, measured_data_dir, lambda c: None, "--configfile", "config/loop_scale.yaml")
    assert out.returncode == 0, out.stderr
    assert out.stdout.count("rule specimen_assemble:") == 6 and "results_loop_scale/specimens/biaxial_full/case5.nc" in out.stdout
    scale, default = load_config(ROOT / "config/loop_scale.yaml"), load_config(ROOT / "config/config.yaml")
    assert (scale["loop"]["cycles"], scale["loop"]["cases"]) == (2000, 6)
    assert asdict(params_from_config("biaxial", scale["rig"])) == {
        **asdict(params_from_config("biaxial", default["rig"])), "mode": "real_time"}
    assert scale["bpm"] == default["bpm"]
    assert scale["loop"]["targets"] == default["loop"]["targets"] + ["sun_et_al_16/p30_q230_f20"]


@pytest.mark.parametrize("change, message", [
    (lambda c: c.update(targets=["sun_et_al_16/p60_q230_f5", "nobody/nothing", "sun_et_al_16/p60_q230_f10"]),
     "loop.targets[1]: 'nobody/nothing' is not a measured test"),
    (lambda c: c.update(targets=["sun_et_al_16/p60_q230_f5"] * 3), "loop.targets[1]: 'sun_et_al_16/p60_q230_f5' given twice"),
    (lambda c: c.update(effects=["rate", "moisture"]), "loop.effects[1]"),
    (lambda c: c.update(targets=["sun_et_al_16/p60_q230_f5"]), "loop.targets"),
])
def test_snakefile_refuses_bad_loop_config(tmp_path, change, message):
    out = _workflow(tmp_path, tmp_path / "no_curves", change)     # refused before any curve is read
    lines = [ln for ln in out.stderr.strip().splitlines() if not ln.startswith("note: ")]
    assert out.returncode == 2 and len(lines) == 1, out.stderr
    assert message in lines[0], lines[0]


def test_a_one_parameter_design_runs_both_bounds():
    """One parameter: an even grid from bound to bound (the bound where an effect is off is
    run, the surrogate never extrapolates); more: the calibration's Latin hypercube."""
    from ballaststudy.calibration.bayes import initial_design
    from ballaststudy.loop.cli import design
    np.testing.assert_allclose(design(np.array([0.0]), np.array([0.2]), 5, 1)[:, 0], [0.0, 0.05, 0.1, 0.15, 0.2])
    np.testing.assert_array_equal(design(np.array([0.0, 1.0]), np.array([1.0, 2.0]), 4, 3),
                                  initial_design([0.0, 1.0], [1.0, 2.0], 4, 3))


def test_a_refinement_round_spans_the_held_out_posteriors():
    """One parameter: midpoints of equal cells over the fold means widened by 3/4 of the
    spacing each side, clipped to the bounds (a bound is never run twice); more: a Latin
    hypercube in that window."""
    from ballaststudy.loop.cli import refined_design
    one = refined_design([[0.3], [0.3]], np.array([0.0]), np.array([1.2]), np.array([0.15]), 4, 0)
    np.testing.assert_allclose(one[:, 0], 0.1875 + 0.05625 * (np.arange(4) + 0.5), rtol=1e-12)
    low = refined_design([[0.01], [0.05]], np.array([0.0]), np.array([1.2]), np.array([0.15]), 2, 0)
    np.testing.assert_allclose(low[:, 0], [0.040625, 0.121875], rtol=1e-12)   # window [0, 0.1625]
    two = refined_design([[0.2, 1.0], [0.4, 3.0]], np.array([0.0, 0.0]), np.array([1.0, 3.5]),
                         np.array([0.1, 1.0]), 16, 7)
    assert two.shape == (16, 2)
    assert np.all(two >= [0.125, 0.25]) and np.all(two <= [0.475, 3.5])
    assert np.ptp(two[:, 0]) > 0.25 and np.ptp(two[:, 1]) > 2.5        # it fills the window
