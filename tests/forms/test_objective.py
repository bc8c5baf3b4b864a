"""Objective of a database (thesis 3.3): mass per size group from the grading, SI/FI as mass
fractions, long-stone mass in the largest groups that can hold a >= 100 mm."""

import numpy as np
import pytest

from ballaststudy.forms.objective import FormParams, ObjectiveError, build_objective


def test_g_crb_b_group_masses(make_definition):
    # G_CRB B mid values: 100, 97.5, 82, 47.5, 13, 1.5, 0, 0 -> per group (% of mass):
    # 80/100: 0 (dropped), 63/80: 2.5, 50/63: 15.5, 40/50: 34.5, 31.5/40: 34.5,
    # 22.4/31.5: 11.5, 16/22.4: 1.5; 8/16 and 4/8: 0 (dropped).
    # LI = L_RB B -> 3 %: 2.5 % fill 63/80, the other 0.5 % go to 50/63 (D = 63 mm can hold
    # a >= 100 mm at a/b <= 2.5). SI_RB 5/30 -> 17.5 % of each group; FI 35 % of each group.
    obj = build_objective("t", make_definition(mass_kg=200.0, grading="G_CRB B", shape_index="SI_RB 5/30",
                                               particle_length_index="L_RB B", flakiness_index="FI_RB 35"))
    names = [g.name for g in obj.groups]
    assert names == ["63/80", "50/63", "40/50", "31.5/40", "22.4/31.5", "16/22.4"], names
    pct = np.array([2.5, 15.5, 34.5, 34.5, 11.5, 1.5])
    got = np.array([g.mass for g in obj.groups])
    np.testing.assert_allclose(got, 2.0 * pct, rtol=1e-12, err_msg="group masses (kg)")
    np.testing.assert_allclose([g.non_cubic for g in obj.groups], 2.0 * pct * 0.175, rtol=1e-12)
    np.testing.assert_allclose([g.flat for g in obj.groups], 2.0 * pct * 0.35, rtol=1e-12)
    np.testing.assert_allclose([g.long for g in obj.groups], [5.0, 1.0, 0, 0, 0, 0], rtol=1e-12, atol=1e-12,
                               err_msg="long mass per group (kg)")
    assert (obj.shape_index, obj.particle_length_index, obj.flakiness_index) == (17.5, 3.0, 35.0)
    g = obj.groups[0]
    assert (g.lower, g.upper) == (0.063, 0.08)


def test_no_fi_target_gives_none(make_definition):
    obj = build_objective("t", make_definition())
    assert obj.flakiness_index is None and all(g.flat is None for g in obj.groups)


@pytest.mark.parametrize("override, key", [
    ({"mass_kg": 0.0}, "mass_kg"),
    ({"mass_kg": -1.0}, "mass_kg"),
    ({"grading": [100, 100, 90, 50, 60, 5, 0, 0]}, "grading[4]"),
    ({"grading": [100, 100, 90, 50, 20, 5, 0, -0.5]}, "grading[7]"),
    ({"grading": [100, 100.5, 90, 50, 20, 5, 0, 0]}, "grading[1]"),
    ({"grading": "G_CRB Q"}, "grading"),
    ({"shape_index": 30, "flakiness_index": 20}, "shape_index"),
    ({"shape_index": "SI_RB 3"}, "shape_index"),
    ({"shape_index": 130}, "shape_index"),
    ({"grading": [100, 100, 100, 100, 100, 50, 10, 0], "particle_length_index": 5}, "particle_length_index"),
    ({"materials": {"x": {"mass_fraction": 0.5, "density_kg_m3": 2700}}}, "materials"),
])
def test_bad_definitions_name_their_key(make_definition, override, key):
    with pytest.raises(ObjectiveError) as err:
        build_objective("t", make_definition(**override))
    assert err.value.key == key, f"key {err.value.key!r}, expected {key!r} ({err.value})"


def test_long_reach_follows_ab_ratio_max(make_definition):
    # all mass in 40/50: with a/b <= 2.5 a 100 mm stone is reachable (b up to 50 mm), with
    # a/b <= 1.9 it is not (50 * 0.98 * 1.9 = 93 mm)
    d = make_definition(grading=[100, 100, 100, 0, 0, 0, 0, 0], particle_length_index=2)
    assert build_objective("t", d, FormParams(ab_ratio_max=2.5)).groups[0].long > 0
    with pytest.raises(ObjectiveError) as err:
        build_objective("t", d, FormParams(ab_ratio_max=1.9))
    assert err.value.key == "particle_length_index"
