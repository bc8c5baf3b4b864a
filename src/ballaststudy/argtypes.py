"""Typed command-line numbers: a value out of its range is refused by argparse in one line
(`argument --cycles: 0 is not allowed; allowed: an integer >= 1 and <= 10000000`), like a
config key, before any work; and the options every stage shares, defined once."""

import argparse
import math
from pathlib import Path

SEED_MAX = 2**63 - 1


def integer(lo, hi):
    """An argparse type: an integer in [lo, hi]."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; allowed: an integer >= {lo} and <= {hi}")
        return value
    return parse


def number(lo, hi):
    """An argparse type: a finite number in [lo, hi]."""
    def parse(text):
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and lo <= value <= hi):
            raise argparse.ArgumentTypeError(f"{text!r} is not allowed; allowed: a number >= {lo:g} and <= {hi:g}")
        return value
    return parse


SEED = integer(0, SEED_MAX)


def add_config(parser):
    """--config: the config file a stage reads its settings from."""
    parser.add_argument("--config", default="config/config.yaml", type=Path,
                        help="the config file (default: config/config.yaml; schema: schemas/config.schema.yaml)")


def add_quiet(parser):
    """--quiet: no progress bars or summary lines (errors are still printed)."""
    parser.add_argument("--quiet", action="store_true", help="no progress or summary output (errors still print)")
