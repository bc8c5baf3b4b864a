"""The scenario tests' shared specimen: a small biaxial specimen of the tiny library."""
from pathlib import Path

import pytest
import yaml

from ..biaxial_fast import FAST_LOADING

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def setup(small_library, tmp_path_factory):
    """(assembled specimen, config, folder): the shipped config with 1000-step windows."""
    from ballaststudy.cli import main
    folder = tmp_path_factory.mktemp("effects")
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / cfg["databases_file"])
    cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING)
    config = folder / "config.yaml"
    config.write_text(yaml.safe_dump(cfg))
    asm = folder / "assembled.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "biaxial",
                 "--width-m", "0.12", "--height-m", "0.24", "--config", str(config),
                 "--out", str(asm), "--quiet"]) == 0
    return asm, config, folder
