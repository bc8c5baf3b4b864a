"""Where a loop's DEM steps went: per test and per set (plain, each effect), from the case
files of a finished loop run.

    python bench/loop_steps.py results/loop/cases

A case's steps are its last sample's step. Counted as run, not as written: a hook-only
effect's case (abrasion) goes on from the plain case's first loading, so only its steps
after cycle 0 count; cases of one first-cycle group (a real-time test's f apart, under one
modifier set) ran cycle 0 once, so it counts once per group (a shared first-loading
failure once in all). Prints steps in millions, runs and failures (in the first loading,
or later). Never a test."""
import argparse
import collections
import json
import os
import sys
from pathlib import Path

import xarray as xr

from ballaststudy.scenario.modifiers import MODIFIERS


def effect_of(modifiers):
    """The case's effect (a modifier of role effect), or plain (material ones only)."""
    effects = [name for name, _ in modifiers if MODIFIERS[name].role != "material"]
    return effects[0] if effects else "plain"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", type=Path, help="a loop's cases/ folder")
    a = ap.parse_args(argv)
    steps, runs, failed_first, failed_later = (collections.Counter() for _ in range(4))
    groups = set()
    files = sorted(a.cases.glob("*/case*.nc"))
    if not files:
        sys.exit(f"{a.cases}: no case files")
    for f in files:
        with xr.open_dataset(f) as ds:
            attrs = dict(ds.attrs)
            last = int(ds.sample_step.values.max())
            first = int(ds.sample_step.values.min())
            ends = ds.cycle_end_step.values
        mods = json.loads(attrs["modifiers_json"])
        effect = effect_of(mods)
        test = os.path.basename(attrs["measured_conditions_file"]).removesuffix(".yaml")
        rig = json.loads(attrs["rig_params_json"])
        gave_way_first = bool(attrs["failed"]) and "first loading" in attrs["failure"]
        c0 = int(ends[0]) if len(ends) else last
        if effect == "abrasion":
            run = last - c0
        else:
            group = (json.dumps(mods, sort_keys=True), rig["confining_pressure_kPa"], rig["deviator_max_kPa"],
                     rig["mode"], f.name)
            cycle0 = c0 - first
            run = (last - c0) + (cycle0 if group not in groups else 0)
            groups.add(group)
        for key in (("test", test), ("set", effect)):
            steps[key] += run
            runs[key] += 1
            failed_first[key] += gave_way_first
            failed_later[key] += bool(attrs["failed"]) and not gave_way_first
    total = sum(v for k, v in steps.items() if k[0] == "test")
    print(f"{len(files)} case files, {total / 1e6:.1f} M steps run")
    for kind in ("test", "set"):
        print(f"\nper {kind}: M steps (share), case files, gave way in the first loading / later")
        for key in sorted(k for k in steps if k[0] == kind):
            print(f"  {key[1]:22s} {steps[key] / 1e6:7.1f} ({steps[key] / total:5.1%})  {runs[key]:3d}  "
                  f"{failed_first[key]:3d} / {failed_later[key]:d}")


if __name__ == "__main__":
    main()
