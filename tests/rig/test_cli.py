"""`ballaststudy case assemble|run` end to end on the small case, with an interruption."""
import json

import pytest
import xarray as xr

from ballaststudy.cli import main
from ballaststudy.rig.params import RigParams

from .conftest import SMALL
from ..shipped import shipped_config


@pytest.fixture
def small_config(tmp_path):
    def small(cfg):
        for stage, keys in RigParams(**SMALL).to_config()["box"].items():
            cfg["rig"]["box"][stage].update({k: keys[k] for k in SMALL if k in keys})
    return shipped_config(tmp_path / "config.yaml", small)


def test_case_cli_with_resume(small_library, small_config, tmp_path, capsys):
    asm = tmp_path / "case0" / "assembled.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--out", str(asm),
                 "--config", str(small_config), "--quiet"]) == 0
    assert asm.is_file()
    out = tmp_path / "case0" / "metrics.nc"
    args = ["case", "run", str(asm), "--cycles", "2", "--out", str(out), "--config",
            str(small_config)]
    assert main(args + ["--stop-after", "1", "--quiet"]) == 0     # "interrupted"
    assert not out.exists() and out.with_name("metrics.checkpoint.npz").exists()
    assert main(args) == 0
    assert "resuming from" in capsys.readouterr().out
    with xr.open_dataset(out) as ds:
        assert ds.sizes["cycle"] == 2
        assert ds["settlement"].attrs["units"] == "m"
        assert ds.attrs["Conventions"] == "CF-1.8"
    with xr.open_dataset(asm) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8"
    for name in ("case.png", "behaviours.png"):
        assert out.with_name(name).stat().st_size > 1000
    assert sorted(p.name for p in out.with_name("vtk").iterdir())[:1] == ["balls_cycle00000.vtp"]
    # provenance beside both outputs, the run's record naming the assembled case as its input
    run_record = json.loads(out.with_name("metrics.nc.prov.json").read_text())
    assert str(asm) in run_record["inputs"] and run_record["step"] == "case run"
    assert json.loads(asm.with_name("assembled.nc.prov.json").read_text())["step"] == "case assemble"


def test_bad_library_is_one_clear_error(small_config, tmp_path, capsys):
    assert main(["case", "assemble", str(tmp_path / "none.nc"), "--case", "0", "--out",
                 str(tmp_path / "a.nc"), "--config", str(small_config)]) == 2
    err = capsys.readouterr().err
    assert "none.nc" in err and "not found" in err
    assert not (tmp_path / "a.nc").exists()
