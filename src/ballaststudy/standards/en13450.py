"""EN 13450 (railway ballast) and EN 933 tables as data, with the thesis' names (ch. 2.1).

Every table keeps the standard's category names. Ranges are (lower, upper) in percent;
a category given as a range is turned into one target number by its mid value (thesis 3.3).
"""

import math
import re

# Table 2-1 / 3-2 sieves (mm), largest first; grading curves are given at these sizes.
GRADING_SIEVES_MM = (80.0, 63.0, 50.0, 40.0, 31.5, 22.4, 16.0, 8.0)

# Size groups d/D used by the generator: the grading sieves, closed above by 100 mm and below
# by 4 mm, the largest and smallest EN 933-3 groups of Table 2-2.
SIZE_GROUP_BOUNDS_MM = (100.0,) + GRADING_SIEVES_MM + (4.0,)

# Table 2-1: percent passing by mass; sieves a category leaves open ("-") are absent.
GRADING_CATEGORIES = {
    "G_CRB A": {80.0: (100, 100), 63.0: (100, 100), 50.0: (70, 99), 40.0: (30, 65),
                31.5: (1, 25), 22.4: (0, 3)},
    "G_CRB B": {80.0: (100, 100), 63.0: (95, 100), 50.0: (65, 99), 40.0: (30, 65),
                31.5: (1, 25), 22.4: (0, 3)},
    "G_CRB C": {80.0: (100, 100), 63.0: (95, 100), 50.0: (55, 99), 40.0: (25, 75),
                31.5: (1, 25), 22.4: (0, 3)},
    "G_CRB D": {80.0: (100, 100), 63.0: (93, 100), 50.0: (45, 70), 40.0: (15, 40),
                31.5: (0, 7), 22.4: (0, 7)},
    "G_CRB E": {50.0: (100, 100), 40.0: (90, 100), 31.5: (60, 98), 22.4: (15, 60),
                16.0: (0, 15), 8.0: (0, 2)},
}

# Table 2-2 (EN 933-3): particle group d_i/D_i (mm) -> nominal slot width of its grid sieve (mm).
GRID_SIEVES = (
    (80.0, 100.0, 50.0), (63.0, 80.0, 40.0), (50.0, 63.0, 31.5), (40.0, 50.0, 25.0),
    (31.5, 40.0, 20.0), (25.0, 31.5, 16.0), (20.0, 25.0, 12.5), (16.0, 20.0, 10.0),
    (12.5, 16.0, 8.0), (10.0, 12.5, 6.3), (8.0, 10.0, 5.0), (6.3, 8.0, 4.0),
    (5.0, 6.3, 3.15), (4.0, 5.0, 2.5),
)

# Tables 2-3 ... 2-5: maximum values (lower, upper) in percent by mass. "Declared" categories
# (FI > 25, SI > 30, LI >= 12) carry the declared number in the name, e.g. "FI_RB 35".
FI_CATEGORIES = {"FI_RB 15": (0, 15), "FI_RB 20": (0, 20), "FI_RB 25": (0, 25), "FI_RB 4/25": (4, 25)}
SI_CATEGORIES = {"SI_RB 10": (0, 10), "SI_RB 20": (0, 20), "SI_RB 30": (0, 30), "SI_RB 5/30": (5, 30)}
LI_CATEGORIES = {"L_RB A": (0, 4), "L_RB B": (0, 6), "L_RB C": (0, 8), "L_RB D": (0, 12)}
_DECLARED_ABOVE = {"FI_RB": 25.0, "SI_RB": 30.0, "L_RB": 12.0}
_TABLES = {"FI_RB": FI_CATEGORIES, "SI_RB": SI_CATEGORIES, "L_RB": LI_CATEGORIES}

NON_CUBIC_RATIO = 3.0          # EN 933-4: non-cubic when L/E > 3 (a/c > 3)
LONG_STONE_LENGTH_MM = 100.0   # EN 13450: long when length >= 100 mm


def canonical_name(name):
    """'g_crb  b', 'GCRB B', 'SI_RB5/30' -> the standard's spelling used as table key."""
    s = re.sub(r"[\s_]+", "", str(name)).upper()
    for prefix, canon in (("GCRB", "G_CRB"), ("FIRB", "FI_RB"), ("SIRB", "SI_RB"), ("LRB", "L_RB")):
        if s.startswith(prefix):
            rest = s[len(prefix):]
            return f"{canon} {rest}" if rest else canon
    return str(name).strip()


def category_target(prefix, value):
    """Target percent for a shape category (prefix 'FI_RB', 'SI_RB' or 'L_RB') or a number.

    Ranges give their mid value (thesis 3.3); a declared category ('FI_RB 35') gives its
    number, which must lie above the table's last category. Raises ValueError naming the
    allowed names.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    name = canonical_name(value)
    table = _TABLES[prefix]
    if name in table:
        lo, hi = table[name]
        return 0.5 * (lo + hi)
    m = re.fullmatch(rf"{prefix} (\d+(?:\.\d+)?)", name)
    if m and float(m.group(1)) > _DECLARED_ABOVE[prefix]:
        return float(m.group(1))
    allowed = ", ".join(table) + f", or '{prefix} <declared value > {_DECLARED_ABOVE[prefix]:g}>'"
    raise ValueError(f"unknown category {value!r}; allowed: {allowed}, or a number 0-100")


def grading_target(value):
    """Percent passing at every sieve of GRADING_SIEVES_MM (tuple, largest sieve first).

    A category name gives the mid value of each range; sieves the category leaves open are
    100 % above its largest specified sieve and 0 % below its smallest (assumption: no
    stones outside the sizes the category talks about). A mapping {sieve_mm: percent}
    or a list in the order of GRADING_SIEVES_MM must give every sieve.
    """
    if isinstance(value, str):
        name = canonical_name(value)
        if name not in GRADING_CATEGORIES:
            raise ValueError(f"unknown grading category {value!r}; allowed: "
                             + ", ".join(GRADING_CATEGORIES) + ", or percent passing per sieve")
        ranges = GRADING_CATEGORIES[name]
        top = max(ranges)
        return tuple(0.5 * sum(ranges[s]) if s in ranges else (100.0 if s > top else 0.0)
                     for s in GRADING_SIEVES_MM)
    if isinstance(value, (list, tuple)):
        if len(value) != len(GRADING_SIEVES_MM):
            raise ValueError(f"{len(value)} percent-passing values given; give one for each sieve "
                             + ", ".join(f"{x:g}" for x in GRADING_SIEVES_MM) + " mm")
        return tuple(float(v) for v in value)
    out = []
    for s in GRADING_SIEVES_MM:
        key = next((k for k in value if math.isclose(float(k), s)), None)
        if key is None:
            raise ValueError(f"percent passing missing for sieve {s:g} mm; give all of "
                             + ", ".join(f"{x:g}" for x in GRADING_SIEVES_MM))
        out.append(float(value[key]))
    return tuple(out)


def grid_slot_width_mm(b_mm):
    """Slot width (mm) of the grid sieve of the EN 933-3 particle group d_i <= b < D_i.

    NaN outside 4-100 mm, where Table 2-2 defines no group (such a stone is never flat).
    """
    for d, big_d, slot in GRID_SIEVES:
        if d <= b_mm < big_d:
            return slot
    return math.nan
