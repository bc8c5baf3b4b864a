"""EN 13450 / EN 933 in code: sieve tables, categories and classification of an aggregate."""

from .en13450 import (
    FI_CATEGORIES,
    GRADING_CATEGORIES,
    GRADING_SIEVES_MM,
    GRID_SIEVES,
    LI_CATEGORIES,
    LONG_STONE_LENGTH_MM,
    NON_CUBIC_RATIO,
    SI_CATEGORIES,
    SIZE_GROUP_BOUNDS_MM,
    category_target,
    grading_target,
    grid_slot_width_mm,
)
from .classify import (
    Classification, classify_aggregate, percent_passing, sieve_group, size_diversity, stone_flags,
)

__all__ = [
    "FI_CATEGORIES", "GRADING_CATEGORIES", "GRADING_SIEVES_MM", "GRID_SIEVES", "LI_CATEGORIES",
    "LONG_STONE_LENGTH_MM", "NON_CUBIC_RATIO", "SI_CATEGORIES", "SIZE_GROUP_BOUNDS_MM", "category_target",
    "grading_target", "grid_slot_width_mm", "Classification", "classify_aggregate",
    "percent_passing", "sieve_group", "size_diversity", "stone_flags",
]
