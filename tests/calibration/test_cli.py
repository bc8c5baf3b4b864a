"""Bad input to the calibration, each one line naming file, key and what is allowed, exit 2,
before any case runs: through `config check` (what the workflow reads first), the
Snakefile (a dry run) and `ballaststudy calibrate` itself."""
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from ballaststudy.cli import main
from ballaststudy.config import ConfigError

from ..biaxial_fast import FAST_LOADING
from ..shipped import shipped_config

ROOT = Path(__file__).resolve().parents[2]


def _config(tmp_path, change):
    return shipped_config(tmp_path / "config.yaml", lambda cfg: change(cfg["calibration"]))


def _copy_workflow(tmp_path):
    for part in ("workflow", "config"):
        src = ROOT / part
        (shutil.copytree(src, tmp_path / part, symlinks=False) if src.is_dir() else shutil.copy(src, tmp_path))


@pytest.mark.parametrize("change, key, allowed", [
    (lambda c: c["parameters"].update(nu={"min": 0.1, "max": 0.2}), "calibration.parameters.nu",
     "unknown key"),
    (lambda c: c["parameters"].update(mu_r={"min": 0.1, "max": 0.2}), "calibration.parameters.mu_r",
     "allowed: with rig.biaxial.assembly.rolling_resistance epsd"),
    (lambda c: c["parameters"].update(E_star={"min": 0, "max": 2e9}), "calibration.parameters.E_star.min", "> 0"),
    (lambda c: c["parameters"].update(kappa_star={"min": 3.0, "max": 2.0}), "calibration.parameters.kappa_star.min",
     "must be below calibration.parameters.kappa_star.max"),
    (lambda c: c["parameters"]["mu"].update(min=-0.1), "calibration.parameters.mu.min", ">= 0"),
    (lambda c: c["parameters"]["F_str_co"].update(min=0.0), "calibration.parameters.F_str_co.min", "> 0"),
    (lambda c: c["parameters"]["F_str_co"].update(min=6.0, max=2.0), "calibration.parameters.F_str_co.min",
     "must be below calibration.parameters.F_str_co.max"),
    (lambda c: c["parameters"]["mu"].pop("max"), "calibration.parameters.mu.max", "missing"),
    (lambda c: c.update(cases=1), "calibration.cases", ">= 2"),
    (lambda c: c.update(targets=["nobody/nothing"]), "calibration.targets[0]", "allowed: sun_et_al_16/p30_q230_f10"),
    (lambda c: c.update(targets=["sun_et_al_16/p60_q230_f5", "sun_et_al_16/p60_q230_f10"]), "calibration.name",
     "required with more than one target"),
    (lambda c: c.update(targets=[]), "calibration.targets", "a list of 1 to 100 items"),
])
def test_bad_calibration_config_is_one_line(tmp_path, capsys, change, key, allowed):
    config = _config(tmp_path, change)
    assert main(["config", "check", "--config", str(config)]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and f"{config}: {key}" in line and allowed in line, line


def test_snakefile_refuses_a_target_that_is_no_test(tmp_path):
    _copy_workflow(tmp_path)
    cfg_path = tmp_path / "config" / "config.yaml"
    cfg = yaml.safe_load(cfg_path.read_text())
    cfg["calibration"]["targets"] = ["nobody/nothing"]
    cfg_path.write_text(yaml.safe_dump(cfg))
    out = subprocess.run(["snakemake", "--cores", "1", "-n", "calibrate"], cwd=tmp_path,
                         capture_output=True, text=True)
    lines = [ln for ln in out.stderr.strip().splitlines() if not ln.startswith("note: ")]
    assert out.returncode == 2 and len(lines) == 1, out.stderr
    assert "config.yaml: calibration.targets[0]: 'nobody/nothing' is not a measured test" in lines[0]


def test_calibrate_checks_before_any_case(measured_target, tmp_path, capsys):
    """K specimens must match calibration.cases; the measured points must reach into the
    simulated cycles; nothing is written then."""
    test, measured = measured_target
    out = tmp_path / "cal"
    for change, argv_specimens, key in (
            (lambda c: c.update(cases=2), ["a.nc"], "calibration.cases: 2 but 1 specimens given"),
            (lambda c: c.update(cases=2, cycles=1), ["a.nc", "b.nc"], "calibration.cycles: 1 cycles hold 1 measured point")):
        config = _config(tmp_path, change)
        args = ["calibrate", str(measured), "--conditions", str(test), "--specimens",
                *[str(tmp_path / s) for s in argv_specimens], "--out-dir", str(out), "--config", str(config)]
        assert main(args) == 2
        line = capsys.readouterr().err.strip()
        assert "\n" not in line and key in line, line
    assert not any(out.rglob("*"))


def test_study_follows_the_calibration_when_asked(tmp_path, measured_data_dir):
    """study.parameters: calibrated -> every box case run depends on the calibrate target's
    calibrated.yaml (so the study reruns when the calibration changes)."""
    _copy_workflow(tmp_path)
    cfg_path = tmp_path / "config" / "config.yaml"
    cfg = yaml.safe_load(cfg_path.read_text())
    cfg["measured"]["data_dir"] = str(measured_data_dir)
    cfg["databases"] = ["box_test"]
    cfg["study"].update(parameters="calibrated", cases_per_database=1)
    cfg_path.write_text(yaml.safe_dump(cfg))
    out = subprocess.run(["snakemake", "--cores", "1", "-n", "-p", "study_aggregate"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "rule calibrate:" in out.stdout and "rule specimen_assemble:" in out.stdout
    target = cfg["calibration"]["targets"][0]
    assert f"--parameters results/calibration/{target}/calibrated.yaml" in out.stdout


def test_case_run_takes_calibrated_parameters(small_library, tmp_path, capsys):
    """`case run --parameters calibrated.yaml`: applied (metrics.nc says so, the record lists
    the file); an unknown name or a value out of range is one line, exit 2."""
    import json

    import xarray as xr
    asm = tmp_path / "assembled.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "biaxial",
                 "--width-m", "0.12", "--height-m", "0.24", "--out", str(asm), "--quiet"]) == 0
    good = tmp_path / "calibrated.yaml"
    good.write_text(yaml.safe_dump({"parameters": {"F_str_co": 7.0, "mu": 0.5}}))
    config = _config(tmp_path, lambda c: None)
    cfg = yaml.safe_load(config.read_text())
    cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING, deviator_max_kPa=60.0)
    config.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "m" / "metrics.nc"
    assert main(["case", "run", str(asm), "--cycles", "1", "--parameters", str(good), "--config",
                 str(config), "--out", str(out), "--no-vtk", "--no-figures", "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.attrs["material_parameters"] == f"calibrated ({good})"
        assert json.loads(ds.attrs["material_parameters_json"]) == {"F_str_co": 7.0, "mu": 0.5}
    record = json.loads(out.with_name("metrics.nc.prov.json").read_text())
    assert str(good) in json.dumps(record["inputs"]) and record["params"]["material_parameters"] == {"F_str_co": 7.0, "mu": 0.5}
    for bad, key in (({"nu": 1.0}, "parameters.nu: unknown parameter"),
                     ({"mu_r": 0.1}, "parameters.mu_r: the specimens' contact law"),
                     ({"F_str_co": 0.0}, "parameters.F_str_co: 0.0 is not allowed; allowed: a number > 0"),
                     ({"mu": -1}, "parameters.mu: -1 is not allowed")):
        path = tmp_path / "bad.yaml"
        path.write_text(yaml.safe_dump({"parameters": bad}))
        capsys.readouterr()
        assert main(["case", "run", str(asm), "--cycles", "1", "--parameters", str(path), "--config",
                     str(config), "--out", str(tmp_path / "x" / "metrics.nc"), "--quiet"]) == 2
        line = capsys.readouterr().err.strip()
        assert "\n" not in line and f"{path}: {key}" in line, line


def test_the_registry_decides_what_is_calibrated(tmp_path):
    """One physical range per parameter, the material modifier's: every material modifier
    is accepted within its range and refused just outside it (no list in the schema to
    keep in step); the schema's default parameters are material modifiers."""
    from ballaststudy.calibration.cli import check_parameters
    from ballaststudy.scenario.modifiers import MATERIAL, material_parameter
    from ballaststudy.schema import load_schema
    default = load_schema("config")["properties"]["calibration"]["properties"]["parameters"]["default"]
    assert set(default) <= set(MATERIAL) and len(MATERIAL) == 5
    for name in MATERIAL:
        p = material_parameter(name)
        check_parameters({name: {"min": p.low + (1e-9 if p.open_low else 0.0), "max": p.high}}, "c.yaml")
        for bad in ({"min": p.low - (0.0 if p.open_low else 1e-9), "max": p.high},
                    {"min": p.low + 1e-3, "max": p.high * 1.001}):
            with pytest.raises(ConfigError, match=f"calibration.parameters.{name}"):
                check_parameters({name: bad}, "c.yaml")


def _workflow_copy(tmp_path, change):
    _copy_workflow(tmp_path)
    box = tmp_path / "config" / "measured" / "planted"
    box.mkdir()
    (box / "box.yaml").write_text(yaml.safe_dump(dict(
        source="planted", rig="box", load_max_kN=40.0,
        curves=[dict(file="s.dat", quantity="settlement", units="mm", sign="compression_positive")])))
    (box / "s.dat").write_text("1, 0.0\n2, 0.1\n5, 0.2\n")
    cfg_path = tmp_path / "config" / "config.yaml"
    cfg = yaml.safe_load(cfg_path.read_text())
    change(cfg["calibration"])
    cfg_path.write_text(yaml.safe_dump(cfg))
    return subprocess.run(["snakemake", "--cores", "1", "-n", "-p", "calibrate"], cwd=tmp_path,
                          capture_output=True, text=True)


def test_a_box_target_is_calibrated_on_box_specimens(tmp_path):
    """A box set is the study's assembled box cases: no biaxial specimen is assembled."""
    out = _workflow_copy(tmp_path, lambda c: c.update(targets=["planted/box"], quantity="settlement",
                                                       specimens="box", cases=2))
    assert out.returncode == 0, out.stderr
    assert "rule case_assemble:" in out.stdout and "--rig biaxial" not in out.stdout
    assert "results/cases/box_test/case0/assembled.nc" in out.stdout
    assert "--width-m" not in out.stdout          # the box keeps the rig's size


@pytest.mark.parametrize("change, message", [
    (lambda c: c.update(targets=["planted/box"]), "calibration.quantity: axial_strain: the box rig"),
    (lambda c: c.update(targets=["planted/box"], quantity="settlement"),
     "calibration.specimens: 'biaxial_small' is a biaxial set, the targets need the box rig"),
    (lambda c: c.update(specimens="box", cases=2), "calibration.specimens: 'box' is a box set, the targets need the biaxial rig"),
    (lambda c: c.update(specimens="nothing"), "calibration.specimens: 'nothing' is not a specimen set"),
    (lambda c: c.update(cases=4), "calibration.cases: 4, but the set 'biaxial_small' has 3"),
    (lambda c: c.update(targets=["planted/box", "sun_et_al_16/p60_q230_f5"], name="mixed"),
     "calibration.targets: planted/box, sun_et_al_16/p60_q230_f5 need the biaxial and box rigs"),
])
def test_snakefile_refuses_targets_the_rig_cannot_run(tmp_path, change, message):
    out = _workflow_copy(tmp_path, change)
    lines = [ln for ln in out.stderr.strip().splitlines() if not ln.startswith("note: ")]
    assert out.returncode == 2 and len(lines) == 1, out.stderr
    assert message in lines[0], lines[0]
