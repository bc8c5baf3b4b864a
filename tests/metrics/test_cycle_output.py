import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from ballaststudy.config import validate
from ballaststudy.metrics import (VARIABLES, MetricsParams, RigGeometry, compute_cycle, read_metrics,
                                  write_metrics)

ROOT = Path(__file__).resolve().parents[2]
R = 0.01
GEOM = RigGeometry(container_x_min=0.0, container_x_max=0.34, container_y_bottom=0.0,
                   plate_x_mid=0.17, plate_bottom_y=0.18, plate_half_width=0.06)
SEG = 0.34 / 20


def snapshot(sink=0.0, intact=True, end_step=2000):
    """Four scenes' worth of stones in one: a 2-ball stone on the bottom (touches the
    container), a 2-ball stone in the middle, a lone ball in the shoulder, a lone ball in the
    middle touching nothing; one plate pebble."""
    pos = np.array([[0.10, 0.01], [0.12, 0.01],       # stone 0 (on the bottom)
                    [0.17, 0.10], [0.19, 0.10],       # stone 1
                    [0.30, 0.19],                     # stone 2, shoulder
                    [0.05, 0.10],                     # stone 3, free
                    [0.17, 0.19]])                    # plate pebble
    t = np.arange(38) / 38
    f = 30e3 - 15e3 * np.cos(2 * np.pi * t)
    return dict(
        pos=pos, rad=np.full(7, R), ballast=np.array([True] * 6 + [False]),
        bond_i=np.array([0, 2]), bond_j=np.array([1, 3]), bond_intact=np.array([True, intact]),
        contact_i=np.array([1, 2, 6]), contact_j=np.array([2, 3, 2]), contact_fn=np.array([10.0, 5.0, 50.0]),
        geometry=GEOM,
        bottom_force=np.full(20, 10.0), bottom_x_centre=SEG * (np.arange(20) + 0.5), bottom_width=np.full(20, SEG),
        load_y=0.25 - sink - 1e-3 * t, load_force=f,
        break_step=np.array([1500, 1600]), break_mode=np.array(["tension", "shear"]),
        n_bonds_installed=2, cycle_start_step=1000, cycle_end_step=end_step)


def test_compute_cycle_all_behaviours():
    row0 = compute_cycle(snapshot())
    assert row0["settlement"] == 0.0
    row = compute_cycle(snapshot(sink=2e-3, intact=False), y_reference=row0["y_at_level"])
    assert row["settlement"] == pytest.approx(2e-3, abs=1e-9), f"measured {row['settlement']}"
    assert row["breakage_rate_tension"] == 0.5 and row["breakage_rate_shear"] == 0.5
    assert row["breakages_per_cycle"] == 2
    x = 0.9 * 0.17
    assert row["x90_left"] == pytest.approx(x) and row["x90_right"] == pytest.approx(x)
    assert row["fpa"] == pytest.approx(math.degrees(math.atan2(0.18, x)))
    # intact: stones 0 {1}, 1 {0, plate}, 2 {}, 3 {} -> mean 3/4; stone 0 container,
    # stone 2 shoulder -> ghosts: 1 (2 contacts) and 3 (0 contacts)
    assert row0["n_fragments"] == 4 and row0["mean_coordination"] == pytest.approx(3 / 4)
    assert row0["excluded_container"] == 1 and row0["excluded_shoulder"] == 1
    assert row0["ghost_particles"] == 2, f"measured {row0['ghost_particles']}"
    # broken bond 2-3: stone 1 -> balls 2 | 3: 0 {2}; 2 {0, 3, plate}; 3 {2}; + 2 lone
    assert row["n_fragments"] == 5 and row["mean_coordination"] == pytest.approx(5 / 5)
    # void ratio: two bonded touching pairs (stadia 4R^2 + pi R^2) + the free ball; the
    # shoulder ball lies wholly above the plate bottom and the pebble is not ballast
    area = 0.34 * 0.18
    solid = 2 * (4 * R * R + math.pi * R * R) + math.pi * R * R
    expected = 1 - solid / area
    assert row0["void_ratio"] == pytest.approx(expected, rel=1e-4), f"measured {row0['void_ratio']}, expected {expected}"
    exp_balls = 1 - 5 * math.pi * R * R / area
    assert row0["void_ratio_balls"] == pytest.approx(exp_balls, rel=1e-4), f"measured {row0['void_ratio_balls']}"


def test_metrics_nc_round_trip(tmp_path):
    rows, ref = [], None
    for k, sink in enumerate([0.0, 1e-3, 1.5e-3]):
        r = compute_cycle(snapshot(sink=sink, intact=k == 0), y_reference=ref)
        ref = r["y_at_level"] if ref is None else ref
        rows.append(r)
    path = tmp_path / "case" / "metrics.nc"
    write_metrics(path, rows, attrs={"case": "test"})
    assert sorted(p.name for p in path.parent.iterdir()) == ["metrics.nc"], "temp file left behind"
    ds = read_metrics(path)
    assert ds.sizes["cycle"] == 3 and ds.attrs["case"] == "test"
    for name in list(ds.data_vars) + ["cycle"]:
        assert ds[name].attrs.get("units") and ds[name].attrs.get("long_name"), f"{name} lacks units/long_name"
    assert set(ds.data_vars) == set(rows[0]) <= set(VARIABLES)   # what the box gives, no more
    assert np.allclose(ds.settlement.values, [0, 1e-3, 1.5e-3], atol=1e-9), ds.settlement.values
    assert ds.fpa.attrs["units"] == "degree" and ds.settlement.attrs["units"] == "m"
    for name in rows[0]:
        assert np.allclose(ds[name].values, [r[name] for r in rows], equal_nan=True), name


def test_failed_write_leaves_old_file(tmp_path):
    path = tmp_path / "metrics.nc"
    write_metrics(path, [compute_cycle(snapshot())])
    before = path.read_bytes()
    with pytest.raises(KeyError):
        write_metrics(path, [{"settlement": 0.0, "mystery": 1.0}])
    assert path.read_bytes() == before and len(list(tmp_path.iterdir())) == 1


def test_config_section_validates_and_maps_to_params():
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    validate(cfg, "config", "config/config.yaml")
    p = MetricsParams.from_config(cfg["metrics"])
    assert p.settlement_force == pytest.approx(30e3), p
    assert p.shoulder_depth == pytest.approx(cfg["metrics"]["shoulder_depth_mm"] * 1e-3)
    with pytest.raises(Exception, match="ghost_max_contacts"):
        validate({**cfg, "metrics": {"ghost_max_contacts": -1}}, "config", "config/config.yaml")
