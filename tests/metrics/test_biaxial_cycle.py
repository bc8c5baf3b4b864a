"""The cyclic biaxial test's behaviours of one cycle (metrics.biaxial.compute_biaxial_cycle)
from a tiny snapshot: breakage rates, strains, fragments, coordination and void ratio, and
the snapshot left as it was (a compute never changes the state)."""
import copy

import numpy as np
import pytest

from ballaststudy.metrics import (BiaxialGeometry, MetricsParams, compute_biaxial_cycle,
                                  metrics_dataset, specimen_strains)

R = 0.01


def snapshot(intact=True):
    """A 2-ball stone and a lone ball touching it in a 0.1 x 0.1 rectangle; one dead ball
    (not ballast). The specimen shrank from 0.1 x 0.1 to 0.098 x 0.101 since consolidation."""
    return dict(
        pos=np.array([[0.03, 0.05], [0.05, 0.05], [0.07, 0.05], [0.5, 0.5]]),
        rad=np.full(4, R), ballast=np.array([True, True, True, False]),
        bond_i=np.array([0]), bond_j=np.array([1]), bond_intact=np.array([intact]),
        contact_i=np.array([1, 0]), contact_j=np.array([2, 1]), contact_fn=np.array([5.0, 3.0]),
        geometry=BiaxialGeometry(x_left=0.0, x_right=0.1, y_bottom=0.0, y_top=0.1),
        height=0.098, width=0.101, height0=0.1, width0=0.1,
        break_step=np.array([500, 1500, 1600]), break_mode=np.array([1, 1, 2]),
        n_bonds_installed=4, cycle_start_step=1000, cycle_end_step=2001)


def test_specimen_strains_compression_positive():
    ea, ev = specimen_strains(0.098, 0.101, 0.1, 0.1)
    assert ea == pytest.approx(0.02) and ev == pytest.approx(1 - 0.098 * 0.101 / 0.01)
    assert specimen_strains(0.1, 0.1, 0.1, 0.1) == (0.0, 0.0)


def test_compute_biaxial_cycle():
    snap = snapshot()
    before = copy.deepcopy(snap)
    row = compute_biaxial_cycle(snap)
    # breakages: 2 tension (one before the cycle), 1 shear of 4 bonds; 2 in this cycle
    assert row["breakage_rate_tension"] == 0.5 and row["breakage_rate_shear"] == 0.25
    assert row["breakage_rate"] == 0.75 and row["breakages_per_cycle"] == 2
    assert row["axial_strain"] == pytest.approx(0.02)
    assert row["volumetric_strain"] == pytest.approx(1 - 0.098 * 0.101 / 0.01)
    # fragments: {0, 1} and {2}; the internal contact 0-1 does not count
    assert row["n_fragments"] == 2 and row["mean_coordination"] == 1.0
    disks = 3 * np.pi * R ** 2 / 0.01
    assert row["void_ratio_balls"] == pytest.approx(1 - disks, abs=1e-3)
    assert 0 < row["void_ratio"] < row["void_ratio_balls"]
    for k, v in before.items():        # nothing changed
        assert v == snap[k] if k == "geometry" else np.array_equal(v, snap[k]), k
    broken = compute_biaxial_cycle(snapshot(intact=False), MetricsParams())
    assert broken["n_fragments"] == 3 and broken["mean_coordination"] == pytest.approx(4 / 3)
    ds = metrics_dataset([row, broken])      # every key is a metrics.nc variable
    assert ds.sizes["cycle"] == 2 and ds["axial_strain"].attrs["units"] == "1"


def test_compute_biaxial_cycle_names_a_missing_key():
    snap = snapshot()
    del snap["height0"]
    with pytest.raises(KeyError, match="height0"):
        compute_biaxial_cycle(snap)
