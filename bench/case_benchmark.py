"""Box-test case benchmark: one case at the config's (thesis-like) resolution.

    NUMBA_NUM_THREADS=1 python bench/case_benchmark.py [--cycles 50] [--r0 0.0025]
        [--config config/config.yaml] [--library BPM.nc] [--dt-factor F]

Uses the BPM library given, else builds the box_test database's forms and BPM library with
the config (cached in results/bench_cache; a few minutes once), or with --synthetic a
synthetic library in the bpm format (ball radius r0, stones 22.4-63 mm); the rig
parameters are the config's. Prints assembly and static
loading times separately, then time per cycle, balls, bonds, steps per cycle and, LAST,
``minutes_per_1000_cycles=<x>`` extrapolated from the cyclic phase. Never a test."""
import argparse
import os
import sys
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")



def box_test_library(config, cache="results/bench_cache"):
    """forms + BPM library of the box_test database (built once, then reused)."""
    from ballaststudy.cli import main as cli
    bpm = os.path.join(cache, "box_test_bpm.nc")
    if not os.path.exists(bpm):
        t = time.perf_counter()
        forms = os.path.join(cache, "box_test.nc")
        if not os.path.exists(forms):
            cli(["forms", "generate", "box_test", "--out", cache, "--config", config, "--quiet"])
        cli(["bpm", "build", forms, "--out", bpm, "--config", config, "--quiet"])
        print(f"built {bpm} in {time.perf_counter() - t:.0f} s (not timed below)")
    return bpm


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=50)
    ap.add_argument("--r0", type=float, default=0.0025, help="ball radius of the synthetic library [m]")
    ap.add_argument("--library", help="a BPM.nc (default: build box_test's)")
    ap.add_argument("--synthetic", action="store_true", help="synthetic library instead")
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--dt-factor", type=float, help="override rig.loading_dt_factor (density scaling)")
    a = ap.parse_args(argv)
    from ballaststudy.config import load_config
    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.library import Library, load_library, synthetic_library
    from ballaststudy.rig.loading import LoadingRun
    from ballaststudy.rig.params import RigParams
    params = RigParams.from_config(load_config(a.config).get("rig", {}))
    if a.dt_factor is not None:
        params.loading_dt_factor = a.dt_factor
    if a.synthetic:
        lib = Library(synthetic_library(60, size=(0.0224, 0.063), r0=a.r0, seed=a.seed,
                                        database="bench"))
    else:
        lib = load_library(a.library or box_test_library(a.config))
    t0 = time.perf_counter()
    rig = assemble(lib, params, seed=a.seed)
    t_asm = time.perf_counter() - t0
    nb, nf = rig.stone_balls().size, int((rig.sim.bonds.active == 1).sum())
    print(f"assembly: {t_asm:.1f} s, {rig.sim.step} steps, stages {rig.layout.stage_steps}")
    print(f"balls={nb} bonds={nf} dt={rig.sim.dt:.3g} s")
    run = LoadingRun(rig, cycles=a.cycles)
    t1 = time.perf_counter()
    s1 = rig.sim.step
    try:
        while run.s.phase in ("static", "unload"):
            run.advance()
    except RuntimeError as err:
        print(f"static loading failed after {time.perf_counter() - t1:.1f} s, "
              f"{rig.sim.step - s1} steps: {err}")
        us = (time.perf_counter() - t1) / max(1, rig.sim.step - s1) * 1e6
        print(f"time_per_step_us={us:.1f}")
        print("minutes_per_1000_cycles=nan")
        return 1
    t_static = time.perf_counter() - t1
    print(f"static loading: {t_static:.1f} s, {rig.sim.step - s1} steps, loading dt={rig.sim.dt:.3g} s "
          f"(dt factor {params.loading_dt_factor:g})")
    t2, s2 = time.perf_counter(), rig.sim.step
    run.run()
    t_cyc = time.perf_counter() - t2
    steps = rig.sim.step - s2
    per = t_cyc / a.cycles
    print(f"cycles={a.cycles} time_per_cycle_s={per:.3f} steps_per_cycle={steps / a.cycles:.0f} "
          f"time_per_step_us={t_cyc / steps * 1e6:.1f}")
    print(f"minutes_per_1000_cycles={per * 1000 / 60:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
