"""The scenario tests' shared specimen: a small biaxial specimen of the tiny library."""
import pytest

from ..biaxial_fast import FAST_LOADING
from ..shipped import shipped_config


@pytest.fixture(scope="session")
def setup(small_library, tmp_path_factory):
    """(assembled specimen, config, folder): the shipped config with 1000-step windows."""
    from ballaststudy.cli import main
    folder = tmp_path_factory.mktemp("effects")
    config = shipped_config(folder / "config.yaml",
                            lambda cfg: cfg["rig"]["biaxial"]["loading"].update(FAST_LOADING))
    asm = folder / "assembled.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "biaxial",
                 "--width-m", "0.12", "--height-m", "0.24", "--config", str(config),
                 "--out", str(asm), "--quiet"]) == 0
    return asm, config, folder
