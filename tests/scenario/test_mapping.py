"""The declared stress mapping (scenario/mapping.py): r = q_peak_2D(p) / q_peak_lab(p) from
a strength envelope file and the config's lab envelope, the q bounds it sets, its records,
its refusals, and a case run under it (measured_sim's path) that is loaded at r x q_lab and
says so. The envelopes here are planted numbers, not data."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from ballaststudy.config import load_config
from ballaststudy.rig.biaxial import BiaxialParams, assemble_biaxial
from ballaststudy.rig.library import load_library
from ballaststudy.rig.biaxial.strength import StrengthResult, strength_dataset, strength_envelope
from ballaststudy.schema import ConfigError
from ballaststudy.scenario.mapping import StressMapping, mapping_from_config, mapping_markdown, stage_mapping
from ballaststudy.scenario.mapping import read_model_envelope
from ballaststudy.scenario.scenario import conditioned_rig, scenario

from ..biaxial_fast import FAST_LOADING

ROOT = Path(__file__).resolve().parents[2]
LAB = {"citation": "planted: q_peak = 20 p^0.7 kPa, not data", "confining_pressure_kPa": [10.0, 100.0],
       "peak_deviator_kPa": [20 * 10.0 ** 0.7, 20 * 100.0 ** 0.7]}
MODEL = {30.0: [110.0, 130.0], 60.0: [170.0, 190.0]}    # 2D q_peak [kPa] per p, two cases


def _strength(p_kPa, q_peak_kPa, case, reached=True):
    n = np.linspace(0.0, 0.05, 6)
    res = StrengthResult(n, -n, n * 1e3, np.full(6, p_kPa * 1e3), q_peak_kPa * 1e3, 45.0, 0.02, 5.0,
                         reached, 0.001, 1e-3, 1.5e-5, 0.04, 2650.0, 1000, "")
    return strength_dataset(res, p_kPa, {"case": case})


@pytest.fixture
def envelope(tmp_path):
    path = tmp_path / "envelope.nc"
    tests = [_strength(p, q, k, reached=(k == 0)) for p, qs in MODEL.items() for k, q in enumerate(qs)]
    strength_envelope(tests).to_netcdf(path)
    return path


def _config(tmp_path, kind="strength_ratio", **lab):
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / "config" / "databases.yaml")
    cfg["stress_mapping"] = {"kind": kind, "lab_envelope": {**LAB, **lab}}
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return path


def _conditions(p_kPa=30.0, q_min=20.0, q_max=200.0):
    return {"rig": "triaxial", "confining_pressure_kPa": p_kPa, "deviator_min_kPa": q_min,
            "deviator_max_kPa": q_max, "frequency_Hz": 10.0}


def test_ratio_is_the_2d_peak_over_the_lab_peak_at_p(tmp_path, envelope):
    path = _config(tmp_path)
    m = mapping_from_config(load_config(path), path, envelope)
    lab30 = 20 * 30.0 ** 0.7            # log-log interpolation is exact on a power law
    assert m.lab_q_peak_kPa_at(30.0) == pytest.approx(lab30, rel=1e-12)
    assert m.ratio(30.0) == pytest.approx(120.0 / lab30, rel=1e-12)
    assert m.ratio(60.0) == pytest.approx(180.0 / (20 * 60.0 ** 0.7), rel=1e-12)
    params, rec = conditioned_rig("biaxial", {}, _conditions(), mapping=m)
    r = 120.0 / lab30
    assert (params.deviator_min_kPa, params.deviator_max_kPa) == pytest.approx((20.0 * r, 200.0 * r), rel=1e-12)
    assert params.confining_pressure_kPa == 30.0 and params.frequency_Hz == 10.0
    assert rec["stress_mapping"] == "strength_ratio"
    assert rec["stress_mapping_lab_deviator_max_kPa"] == 200.0
    assert rec["stress_mapping_model_peak_share"] == 0.5        # one of the two cases passed its peak
    assert rec["stress_mapping_lab_envelope_citation"] == LAB["citation"]


def test_none_leaves_the_test_and_the_cache_key_as_they_were(tmp_path, envelope):
    plain, rec = conditioned_rig("biaxial", {}, _conditions())
    assert rec == {"stress_mapping": "none"}
    assert (plain.deviator_min_kPa, plain.deviator_max_kPa) == (20.0, 200.0)
    none = mapping_from_config(load_config(_config(tmp_path, "none")), "c.yaml")
    assert conditioned_rig("biaxial", {}, _conditions(), mapping=none)[0].to_dict() == plain.to_dict()
    path = _config(tmp_path)
    mapped, mrec = conditioned_rig("biaxial", {}, _conditions(), mapping=mapping_from_config(load_config(path),
                                                                                              path, envelope))
    spec = str(envelope)                 # any file: the key hashes its content
    key = scenario("biaxial", [spec], plain, 3).key
    assert scenario("biaxial", [spec], plain, 3, mapping=rec).key == key
    assert scenario("biaxial", [spec], mapped, 3, mapping=mrec).key != key
    assert "**none**" in mapping_markdown({"t": rec})
    assert "| t | 30 |" in mapping_markdown({"t": mrec})


def test_a_box_test_is_not_mapped(tmp_path, envelope):
    path = _config(tmp_path)
    assert not stage_mapping(load_config(path), path, None, "box").applied
    with pytest.raises(ConfigError, match="--strength-envelope"):
        stage_mapping(load_config(path), path, envelope, "box")


@pytest.mark.parametrize("change, key", [
    (dict(citation=""), "stress_mapping.lab_envelope.citation"),
    (dict(peak_deviator_kPa=[100.0]), "stress_mapping.lab_envelope.peak_deviator_kPa"),
    (dict(confining_pressure_kPa=[100.0, 10.0]), "stress_mapping.lab_envelope.confining_pressure_kPa"),
    (dict(confining_pressure_kPa=[], peak_deviator_kPa=[]), "stress_mapping.lab_envelope.confining_pressure_kPa"),
])
def test_a_bad_lab_envelope_is_refused_naming_its_key(tmp_path, change, key):
    path = _config(tmp_path, **change)
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        load_config(path)


def test_refusals_name_what_is_missing(tmp_path, envelope):
    path = _config(tmp_path)
    cfg = load_config(path)
    with pytest.raises(ConfigError, match="--strength-envelope: missing"):
        mapping_from_config(cfg, path, None)
    with pytest.raises(ConfigError, match="it would change nothing"):
        mapping_from_config(load_config(_config(tmp_path, "none")), path, envelope)
    m = mapping_from_config(cfg, path, envelope)
    with pytest.raises(ConfigError, match="outside the envelope's 10-100 kPa"):
        m.lab_q_peak_kPa_at(150.0)
    with pytest.raises(ConfigError, match=r"no strength test at p = 45 kPa"):
        conditioned_rig("biaxial", {}, _conditions(p_kPa=45.0), mapping=m)
    assert StressMapping().ratio(45.0) == 1.0


@pytest.fixture(scope="module")
def biaxial_specimen(small_library, tmp_path_factory):
    p = BiaxialParams(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000, fill_area_ratio=0.9)
    path = tmp_path_factory.mktemp("mapping") / "assembled.nc"
    assemble_biaxial(load_library(small_library), p, seed=7).save(path)
    return path


def _run(*args):
    return subprocess.run([sys.executable, "-m", "ballaststudy.cli", *map(str, args)], capture_output=True,
                          text=True, env={**os.environ, "NUMBA_NUM_THREADS": "1"})


def test_a_case_run_under_the_mapping_is_loaded_at_r_times_the_lab_q_and_says_so(
        tmp_path, envelope, biaxial_specimen):
    cfg = yaml.safe_load(_config(tmp_path).read_text())
    cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING)
    lab30 = 2 * 120.0       # planted so that r = 0.5 at p = 30 kPa: a factor of two either way shows
    cfg["stress_mapping"] = {"kind": "strength_ratio", "lab_envelope": {
        "citation": "planted", "confining_pressure_kPa": [30.0], "peak_deviator_kPa": [lab30]}}
    path = tmp_path / "mapped.yaml"
    path.write_text(yaml.safe_dump(cfg))
    cond = tmp_path / "test.yaml"
    cond.write_text(yaml.safe_dump(dict(source="planted", rig="triaxial", confining_pressure_kPa=30.0,
                                        deviator_min_kPa=20.0, deviator_max_kPa=100.0,
                                        curves=[dict(file="a.dat", quantity="axial_strain", units="1",
                                                     sign="compression_positive")])))
    out = tmp_path / "case.nc"
    refused = _run("case", "run", biaxial_specimen, "--cycles", 2, "--conditions", cond, "--config", path,
                   "--out", out, "--no-vtk", "--no-figures", "--quiet")
    assert refused.returncode == 2 and not out.exists()
    assert refused.stderr.strip().count("\n") == 0 and "--strength-envelope: missing" in refused.stderr
    done = _run("case", "run", biaxial_specimen, "--cycles", 2, "--conditions", cond, "--config", path,
                "--strength-envelope", envelope, "--out", out, "--no-vtk", "--no-figures", "--quiet")
    assert done.returncode == 0, done.stderr
    ds = xr.open_dataset(out)
    r = read_model_envelope(envelope)[1][0] / lab30
    assert ds.attrs["stress_mapping"] == "strength_ratio" and ds.attrs["stress_mapping_ratio"] == pytest.approx(r)
    assert ds.attrs["stress_mapping_deviator_max_kPa"] == pytest.approx(100.0 * r)
    assert json.loads(open(str(out) + ".prov.json").read())["params"]["stress_mapping"]["stress_mapping"] \
        == "strength_ratio"
    # sigma_1 peaks at p + r q_max in every cycle (the stress-controlled bounds), not at p + q_max
    peaks = ds["axial_stress_max"].values / 1e3
    np.testing.assert_allclose(peaks, 30.0 + 100.0 * r, rtol=0.03)
