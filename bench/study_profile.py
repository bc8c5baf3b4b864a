"""Where a study's time goes, per database: one box case assembled and loaded per library.

    NUMBA_NUM_THREADS=1 python bench/study_profile.py --bpm-dir results/bpm \
        [--config config/thesis.yaml] [--cycles 20] [--case 0] [--jobs 2] [--databases ...]

For every ``<database>.nc`` in ``--bpm-dir`` (the bpm stage's libraries, built with the
same config), case ``--case`` is assembled with the workflow's seed for it
(rig.params.case_seed) and loaded through static pre-loading and ``--cycles`` load cycles,
as ``ballaststudy case assemble`` / ``case run`` do (without the per-cycle metrics and
files, which cost little: 50 cycles of a box_test case spent 12.5 of 13 s stepping).
Prints per database the stones and balls of the case, the loading dt, assembly seconds and
steps per stage, static seconds, steps and seconds per cycle, and the estimated minutes of
one case with the config's cycles (assembly + static + cycles x seconds per cycle); LAST
the estimated core-hours of the config's cases over these databases and the wall hours on
``--jobs`` cores. Run it alone: cases share the cores. Never a test."""
import argparse
import glob
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def profile_case(library, config, case, cycles):
    """One case of ``library``: sizes, times and steps of its stages."""
    from ballaststudy.config import load_config
    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.library import load_library
    from ballaststudy.rig.loading import LoadingRun
    from ballaststudy.rig.params import RigParams, case_seed
    cfg = load_config(config)
    lib = load_library(library)
    params = RigParams.from_config(cfg.get("rig", {}))
    t0 = time.perf_counter()
    rig = assemble(lib, params, seed=case_seed(cfg["seed"], lib.database, case))
    out = dict(database=lib.database, stones=len(rig.layout.stone_library_index),
               balls=int(rig.stone_balls().size), assembly_s=time.perf_counter() - t0,
               stages=dict(rig.layout.stage_steps), config_cycles=params.cycles)
    run = LoadingRun(rig, cycles=cycles)
    t1 = time.perf_counter()
    while run.s.phase in ("static", "unload"):
        run.advance()
    out["static_s"] = time.perf_counter() - t1
    t2, s2 = time.perf_counter(), rig.sim.step
    run.run()
    out["s_per_cycle"] = (time.perf_counter() - t2) / cycles
    out["steps_per_cycle"] = (rig.sim.step - s2) / cycles
    out["dt"] = rig.sim.dt
    out["case_min"] = (out["assembly_s"] + out["static_s"]
                       + params.cycles * out["s_per_cycle"]) / 60.0
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bpm-dir", required=True, help="folder of the bpm stage's <database>.nc")
    ap.add_argument("--config", default="config/thesis.yaml")
    ap.add_argument("--cycles", type=int, default=20)
    ap.add_argument("--case", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--databases", nargs="*", help="only these (default: every library)")
    a = ap.parse_args(argv)
    libs = sorted(glob.glob(os.path.join(a.bpm_dir, "*.nc")))
    if a.databases:
        libs = [p for p in libs if os.path.basename(p)[:-3] in a.databases]
    with ProcessPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(profile_case, libs, [a.config] * len(libs),
                             [a.case] * len(libs), [a.cycles] * len(libs)))
    print("database   stones  balls  dt_loading_s  assembly_s  static_s  steps_per_cycle  "
          "s_per_cycle  case_min  assembly_stage_steps")
    for r in rows:
        print(f"{r['database']:10} {r['stones']:6d} {r['balls']:6d} {r['dt']:13.3g} "
              f"{r['assembly_s']:11.1f} {r['static_s']:9.1f} {r['steps_per_cycle']:16.0f} "
              f"{r['s_per_cycle']:12.3f} {r['case_min']:9.2f}  {r['stages']}")
    from ballaststudy.config import load_config
    n_cases = int(load_config(a.config).get("study", {}).get("cases_per_database", 10))
    core_h = sum(r["case_min"] for r in rows) * n_cases / 60.0
    print(f"cases: {n_cases} per database x {len(rows)} databases, "
          f"{rows[0]['config_cycles'] if rows else 0} cycles each (estimated from "
          f"{a.cycles} cycles of case {a.case})")
    print(f"estimated_core_hours={core_h:.2f} wall_hours_on_{a.jobs}_cores="
          f"{core_h / a.jobs:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
