"""Classification of stones and aggregates (thesis 2.1, 3.2): sieve group (eq. 3.1), flags
at their boundaries, percent passing, FI/SI/LI, size diversity (eq. 3.3), grading categories.

Float boundaries: the code converts b to mm by `b * 1e3` and compares with the table values.
Each boundary test uses b = D / 1e3 and first asserts that `b * 1e3 == D` holds exactly in
float64 (it does for every sieve of the tables), so "exactly on the sieve" means what it
says; "just below" is b * (1 - 1e-12), far below any sieve and far above round-off.
"""

import numpy as np
import pytest

from ballaststudy.standards import (
    GRADING_SIEVES_MM, SIZE_GROUP_BOUNDS_MM, classify_aggregate, percent_passing, sieve_group,
    size_diversity, stone_flags,
)
from ballaststudy.standards.classify import grading_categories_met, slot_widths_m

BELOW = 1 - 1e-12


def _exact_m(size_mm):
    b = size_mm / 1e3
    assert b * 1e3 == size_mm, f"{size_mm} mm is not round-trip exact as {b!r} m"
    return b


def _group_name(k):
    return f"{SIZE_GROUP_BOUNDS_MM[k + 1]:g}/{SIZE_GROUP_BOUNDS_MM[k]:g}"


def test_b_on_31_5_belongs_to_group_above():
    b = _exact_m(31.5)
    k_on = int(sieve_group(b)[0])
    k_below = int(sieve_group(b * BELOW)[0])
    assert _group_name(k_on) == "31.5/40", f"b = 31.5 mm -> group {_group_name(k_on)}, expected 31.5/40"
    assert _group_name(k_below) == "22.4/31.5", f"b just below 31.5 mm -> {_group_name(k_below)}, expected 22.4/31.5"


@pytest.mark.parametrize("k", range(len(SIZE_GROUP_BOUNDS_MM) - 1))
def test_every_group_boundary(k):
    # group k is d <= b < D with D = bounds[k], d = bounds[k + 1]
    big_d, d = SIZE_GROUP_BOUNDS_MM[k], SIZE_GROUP_BOUNDS_MM[k + 1]
    b = np.array([_exact_m(d), _exact_m(d) / BELOW, 0.5 * (_exact_m(d) + _exact_m(big_d)),
                  _exact_m(big_d) * BELOW])
    got = sieve_group(b)
    assert np.all(got == k), f"group {d:g}/{big_d:g}: sieve_group({b.tolist()}) = {got.tolist()}, expected {k}"


@pytest.mark.parametrize("b_mm", [100.0, 120.0, 3.999, 0.0])
def test_outside_4_100_mm_is_no_group(b_mm):
    assert int(sieve_group(b_mm / 1e3)[0]) == -1
    assert np.isnan(slot_widths_m(b_mm / 1e3)[0])


def test_b_exactly_4mm_is_smallest_group():
    k = int(sieve_group(_exact_m(4.0))[0])
    assert _group_name(k) == "4/8", f"b = 4 mm -> {_group_name(k)}"


def test_slot_widths_boundaries():
    # EN 933-3 groups (Table 2-2) differ from the grading groups: 25 mm starts 25/31.5
    got = slot_widths_m([_exact_m(25.0) * BELOW, _exact_m(25.0), _exact_m(31.5), _exact_m(80.0)])
    expected = np.array([12.5, 16.0, 20.0, 50.0]) * 1e-3
    np.testing.assert_array_equal(got, expected)


def test_flat_iff_c_below_slot():
    b = np.full(3, 0.045)                    # group 40/50, slot 25 mm
    slot = slot_widths_m(b)[0]                # the boundary exactly as the code computes it
    assert slot == 0.025
    c = np.array([slot, np.nextafter(slot, 0.0), slot * BELOW])
    flat, _, _ = stone_flags(np.full(3, 0.06), b, c)
    assert flat.tolist() == [False, True, True], f"c == slot must not be flat: flags {flat.tolist()} for c {c.tolist()}"


def test_flat_switches_with_group_of_b():
    # c = 17 mm: flat in 31.5/40 (slot 20) but not in 25/31.5 (slot 16)
    b = np.array([_exact_m(31.5), _exact_m(31.5) * BELOW])
    flat, _, _ = stone_flags([0.05, 0.05], b, [0.017, 0.017])
    assert flat.tolist() == [True, False]


def test_no_flat_outside_groups():
    flat, _, _ = stone_flags([0.2, 0.003], [0.1, 0.003], [0.001, 0.0001])
    assert not flat.any()


def test_non_cubic_strictly_above_3():
    c = 0.02
    a_eq = 3.0 * c                           # same product the code forms: a > 3.0 * c
    a = np.array([a_eq, np.nextafter(a_eq, 1.0), a_eq * BELOW])
    _, nc, _ = stone_flags(a, np.full(3, 0.03), np.full(3, c))
    assert nc.tolist() == [False, True, False], f"a/c == 3 must be cubic: {nc.tolist()} for a {a.tolist()}"


def test_long_from_100mm_inclusive():
    a = np.array([_exact_m(100.0), _exact_m(100.0) * BELOW, 0.15])
    _, _, long = stone_flags(a, np.full(3, 0.05), np.full(3, 0.04))
    assert long.tolist() == [True, False, True], f"a == 100 mm must be long: {long.tolist()}"


# A hand-made aggregate (mm and kg). Per stone: grading group from b, grid group from b
# (Table 2-2) and its slot, flags:
#  1: a 120, b 70, c 45, 4 kg: slot 40 (63/80) -> not flat; a/c 2.67 cubic; long
#  2: a  70, b 45, c 20, 3 kg: slot 25 (40/50) -> flat;     a/c 3.5 non-cubic; not long
#  3: a  50, b 35, c 25, 2 kg: slot 20 (31.5/40) -> not flat; a/c 2 cubic
#  4: a  30, b 21, c 12, 1 kg: slot 12.5 (20/25) -> flat;   a/c 2.5 cubic
# FI = (3 + 1)/10 = 40 %, SI = 3/10 = 30 %, LI = 4/10 = 40 %.
# Passing (b < sieve): 80: all 100; 63: no 70 -> 60; 50: 60; 40: 35, 21 -> 30; 31.5: 10;
# 22.4: 10; 16: 0; 8: 0.
# SD = 50 + 10 + 10 + 20 + 40 + 40 + 50 + 50 = 270.
HAND = dict(a=np.array([120, 70, 50, 30]) * 1e-3, b=np.array([70, 45, 35, 21]) * 1e-3,
            c=np.array([45, 20, 25, 12]) * 1e-3, mass=np.array([4.0, 3.0, 2.0, 1.0]))
HAND_PASSING = [100, 60, 60, 30, 10, 10, 0, 0]


def test_hand_aggregate_flags():
    flat, nc, long = stone_flags(HAND["a"], HAND["b"], HAND["c"])
    assert flat.tolist() == [False, True, False, True]
    assert nc.tolist() == [False, True, False, False]
    assert long.tolist() == [True, False, False, False]


def test_hand_aggregate_percent_passing():
    got = percent_passing(HAND["b"], HAND["mass"])
    np.testing.assert_allclose(got, HAND_PASSING, rtol=0, atol=1e-12,
                               err_msg="percent passing of the hand-made aggregate")


def test_hand_aggregate_classification():
    cl = classify_aggregate(HAND["a"], HAND["b"], HAND["c"], HAND["mass"])
    got = (cl.flakiness_index, cl.shape_index, cl.particle_length_index, cl.size_diversity,
           cl.total_mass, cl.particle_count)
    expected = (40.0, 30.0, 40.0, 270.0, 10.0, 4)
    np.testing.assert_allclose(got, expected, rtol=1e-12,
                               err_msg="(FI, SI, LI, SD, mass, count) measured vs expected")
    assert cl.fi_categories == [], cl.fi_categories
    assert sorted(cl.si_categories) == ["SI_RB 30", "SI_RB 5/30"], cl.si_categories
    assert cl.li_categories == [], cl.li_categories
    assert cl.grading_categories == [], cl.grading_categories


def test_classification_with_other_sieves_has_no_size_diversity():
    cl = classify_aggregate(HAND["a"], HAND["b"], HAND["c"], HAND["mass"], sieves_mm=(50.0, 30.0))
    np.testing.assert_allclose(cl.percent_passing, [60.0, 10.0], atol=1e-12)
    assert np.isnan(cl.size_diversity)


def test_size_diversity_eq_3_3():
    # |100-50| + |95-50| + |80-50| + |50-50| + |20-50| + |5-50| + |2-50| + |0-50|
    # = 50 + 45 + 30 + 0 + 30 + 45 + 48 + 50 = 298
    curve = [100, 95, 80, 50, 20, 5, 2, 0]
    assert size_diversity(curve) == 298.0


def test_grading_categories_inside_and_outside_g_crb_a():
    mid_a = [100, 100, 84.5, 47.5, 13, 1.5, 0, 0]    # mid values of G_CRB A
    met = grading_categories_met(mid_a)
    assert "G_CRB A" in met, met
    assert "G_CRB B" in met and "G_CRB C" in met, met   # A's ranges lie inside B's and C's
    assert "G_CRB D" not in met and "G_CRB E" not in met, met
    # 69 % at 50 mm: below A's 70 but inside B's 65..99
    below = [100, 100, 69, 47.5, 13, 1.5, 0, 0]
    met = grading_categories_met(below)
    assert "G_CRB A" not in met and "G_CRB B" in met, met
    # the boundary itself is inside: exactly 70 % at 50 mm
    assert "G_CRB A" in grading_categories_met([100, 100, 70, 30, 1, 0, 0, 0])
    # 96 % at 63 mm: A requires 100
    assert "G_CRB A" not in grading_categories_met([100, 96, 84.5, 47.5, 13, 1.5, 0, 0])


def test_grading_sieves_are_the_table_2_1_sieves():
    assert GRADING_SIEVES_MM == (80.0, 63.0, 50.0, 40.0, 31.5, 22.4, 16.0, 8.0)
