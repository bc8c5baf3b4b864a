"""The config's ordered pairs (config.ORDERED_PAIRS: a minimum below its maximum, a plate no
wider than the box, a plate lowered faster than a settled pile moves): each pair out of
order in the default config is refused by `ballaststudy config check` in one line naming
the file and the first key, exit 2; the shipped config passes."""
import shutil
from pathlib import Path

import pytest
import yaml

from ballaststudy.cli import main
from ballaststudy.config import ORDERED_PAIRS, stage_default

REPO = Path(__file__).resolve().parents[2]


def _config_copy(tmp_path):
    for name in ("config.yaml", "databases.yaml"):
        shutil.copy(REPO / "config" / name, tmp_path / name)
    return tmp_path / "config.yaml"


def _check(capsys, path):
    rc = main(["config", "check", "--config", str(path)])
    return rc, capsys.readouterr().err.strip().splitlines()


@pytest.mark.parametrize("section, lo_key, hi_key, strict", ORDERED_PAIRS,
                         ids=[f"{s}.{lo}" for s, lo, _, _ in ORDERED_PAIRS])
def test_pair_out_of_order_is_refused(section, lo_key, hi_key, strict, tmp_path, capsys):
    path = _config_copy(tmp_path)
    assert _check(capsys, path)[0] == 0
    cfg = yaml.safe_load(path.read_text())
    sec = cfg
    for part in section.split("."):
        sec = sec.setdefault(part, {})
    hi = sec.get(hi_key, stage_default(section, hi_key))
    sec[lo_key] = hi if strict else hi * 1.5       # equal is refused only if strict
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    rc, lines = _check(capsys, path)
    assert rc == 2 and len(lines) == 1, lines
    assert "config.yaml" in lines[0] and f"{section}.{lo_key}" in lines[0] and hi_key in lines[0], lines


def test_plate_as_slow_as_a_settled_pile_is_refused(tmp_path, capsys):
    """The plate's slow speed at the settle speed (on a thesis-scale G_2-5 case the plate
    followed the settled pile 10000 moves down without landing)."""
    path = _config_copy(tmp_path)
    cfg = yaml.safe_load(path.read_text())
    assembly = cfg["rig"]["box"]["assembly"]
    assembly["plate_settle_velocity_m_s"] = assembly["settle_speed_m_s"] = 0.01
    path.write_text(yaml.safe_dump(cfg, sort_keys=False))
    rc, lines = _check(capsys, path)
    assert rc == 2 and "rig.box.assembly.settle_speed_m_s" in lines[0], lines
    assert "plate_settle_velocity_m_s" in lines[0], lines
