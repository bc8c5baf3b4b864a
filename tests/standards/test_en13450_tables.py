"""EN 13450 tables as data: category targets (mid values, thesis 3.3), declared categories,
grading targets and the error for an unknown category."""

import math

import pytest

from ballaststudy.standards import (
    FI_CATEGORIES, GRADING_CATEGORIES, GRADING_SIEVES_MM, GRID_SIEVES, LI_CATEGORIES,
    SI_CATEGORIES, SIZE_GROUP_BOUNDS_MM, category_target, grading_target, grid_slot_width_mm,
)
from ballaststudy.standards.en13450 import canonical_name


@pytest.mark.parametrize("prefix, name, expected", [
    ("SI_RB", "SI_RB 5/30", 17.5),     # range 5 to 30 -> mid 17.5
    ("SI_RB", "SI_RB 10", 5.0),        # <= 10 -> range 0..10 -> 5
    ("SI_RB", "si_rb5/30", 17.5),      # spelling variants are accepted
    ("L_RB", "L_RB B", 3.0),           # <= 6 -> 3
    ("L_RB", "L_RB D", 6.0),           # <= 12 -> 6
    ("L_RB", "lrb a", 2.0),
    ("FI_RB", "FI_RB 4/25", 14.5),     # (4 + 25) / 2
    ("FI_RB", "FI_RB 35", 35.0),       # declared (> 25): the number itself
    ("SI_RB", "SI_RB 45", 45.0),       # declared (> 30)
    ("L_RB", "L_RB 13", 13.0),         # declared (> 12)
    ("FI_RB", 12.5, 12.5),             # a plain number is the target
])
def test_category_target(prefix, name, expected):
    got = category_target(prefix, name)
    assert got == expected, f"category_target({prefix!r}, {name!r}) = {got}, expected {expected}"


@pytest.mark.parametrize("prefix, name, must_name", [
    ("SI_RB", "SI_RB 7", ["SI_RB 10", "SI_RB 20", "SI_RB 30", "SI_RB 5/30"]),
    ("FI_RB", "FI_RB 24", ["FI_RB 15", "FI_RB 20", "FI_RB 25", "FI_RB 4/25"]),  # 24 <= 25: not declared
    ("L_RB", "L_RB Z", ["L_RB A", "L_RB B", "L_RB C", "L_RB D"]),
    ("L_RB", "L_RB 12", ["L_RB A", "L_RB D"]),  # declared needs > 12
])
def test_unknown_category_raises_naming_allowed(prefix, name, must_name):
    with pytest.raises(ValueError) as err:
        category_target(prefix, name)
    msg = str(err.value)
    missing = [n for n in must_name if n not in msg]
    assert not missing, f"message {msg!r} does not name {missing}"
    assert name in msg, f"message {msg!r} does not repeat the bad value {name!r}"


def test_canonical_names():
    assert canonical_name("g_crb  b") == "G_CRB B"
    assert canonical_name("GCRB B") == "G_CRB B"
    assert canonical_name("SI_RB5/30") == "SI_RB 5/30"


def test_grading_target_mid_values_g_crb_b():
    # Table 2-1, G_CRB B: 80: 100, 63: 95-100, 50: 65-99, 40: 30-65, 31.5: 1-25, 22.4: 0-3;
    # 16 and 8 mm are open ('-') below the smallest specified sieve -> 0 %.
    expected = (100.0, 97.5, 82.0, 47.5, 13.0, 1.5, 0.0, 0.0)
    got = grading_target("G_CRB B")
    assert got == expected, f"G_CRB B target {got}, expected {expected}"


def test_grading_target_open_sieves_above_are_100():
    # G_CRB E starts at 50 mm (100 %): 80 and 63 mm are open above -> 100 %.
    expected = (100.0, 100.0, 100.0, 95.0, 79.0, 37.5, 7.5, 1.0)
    got = grading_target("G_CRB E")
    assert got == expected, f"G_CRB E target {got}, expected {expected}"


def test_grading_target_list_and_mapping():
    curve = [100, 90, 70, 40, 20, 10, 5, 0]
    assert grading_target(curve) == tuple(float(x) for x in curve)
    mapping = {str(s): v for s, v in zip(GRADING_SIEVES_MM, curve)}
    assert grading_target(mapping) == tuple(float(x) for x in curve)
    with pytest.raises(ValueError, match="8 mm"):
        grading_target(curve[:-1])
    with pytest.raises(ValueError, match="missing for sieve 8 mm"):
        grading_target({s: v for s, v in zip(GRADING_SIEVES_MM[:-1], curve)})


def test_unknown_grading_category_names_allowed():
    with pytest.raises(ValueError) as err:
        grading_target("G_CRB Z")
    msg = str(err.value)
    for name in ("G_CRB A", "G_CRB B", "G_CRB C", "G_CRB D", "G_CRB E"):
        assert name in msg, f"{name} missing in {msg!r}"


def test_tables_are_consistent():
    # grading sieves strictly decreasing; group bounds are them closed by 100 and 4 mm
    assert all(x > y for x, y in zip(GRADING_SIEVES_MM, GRADING_SIEVES_MM[1:]))
    assert SIZE_GROUP_BOUNDS_MM == (100.0,) + GRADING_SIEVES_MM + (4.0,)
    # Table 2-2: groups tile 4..100 mm without gap; slot width D_i / 2 (thesis 3.2.2) within
    # the standard's rounding (31.5 for 63, 6.3 for 12.5, 3.15 for 6.3)
    for (d, big_d, slot), (d_next, big_next, _) in zip(GRID_SIEVES, GRID_SIEVES[1:]):
        assert d == big_next, f"group {d_next}/{big_next} does not join {d}/{big_d}"
    assert GRID_SIEVES[0][1] == 100.0 and GRID_SIEVES[-1][0] == 4.0
    for d, big_d, slot in GRID_SIEVES:
        assert abs(slot - big_d / 2) <= 0.05 * big_d / 2, f"{d}/{big_d}: slot {slot} vs D/2 {big_d / 2}"
    for table in (FI_CATEGORIES, SI_CATEGORIES, LI_CATEGORIES):
        assert all(0 <= lo < hi <= 100 for lo, hi in table.values())
    for name, ranges in GRADING_CATEGORIES.items():
        assert all(0 <= lo <= hi <= 100 for lo, hi in ranges.values()), name


@pytest.mark.parametrize("b_mm, slot", [(4.0, 2.5), (4.999, 2.5), (5.0, 3.15), (31.5, 20.0),
                                        (39.99, 20.0), (99.9, 50.0)])
def test_grid_slot_width_mm(b_mm, slot):
    assert grid_slot_width_mm(b_mm) == slot


@pytest.mark.parametrize("b_mm", [3.99, 100.0, 150.0])
def test_grid_slot_width_outside_groups_is_nan(b_mm):
    assert math.isnan(grid_slot_width_mm(b_mm))
