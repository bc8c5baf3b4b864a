"""Box-test case benchmark: one case at the config's (thesis-like) resolution.

    NUMBA_NUM_THREADS=1 python bench/case_benchmark.py [--cycles 50] [--r0 0.0025]
        [--config config/config.yaml] [--library BPM.nc] [--dt-factor F]
        [--reference /path/to/old/checkout] [--settle2d]

Uses the BPM library given, else builds the box_test database's forms and BPM library with
the config (cached in results/bench_cache; a few minutes once), or with --synthetic a
synthetic library in the bpm format (ball radius r0, stones 22.4-63 mm); the rig
parameters are the config's. Prints assembly and static
loading times separately, then time per cycle, balls, bonds, steps per cycle and, LAST,
``minutes_per_1000_cycles=<x>`` extrapolated from the cyclic phase. With ``--settle2d`` it
also runs the settle2d problem (bench/engine_vs_lammps.py) at the case's ball count and
prints both ball-step rates; with ``--reference SRC`` it first runs SRC's own copy of this
benchmark with SRC's package (a clean checkout of the revision to compare with), so both
are measured in one invocation on the same machine state. Never a test."""
import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")



def box_test_library(config, cache="results/bench_cache"):
    """forms + BPM library of the box_test database under ``config`` (built once per
    config file name, then reused)."""
    from ballaststudy.cli import main as cli
    cache = os.path.join(cache, os.path.splitext(os.path.basename(config))[0])
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
    ap.add_argument("--reference", help="checkout whose own case_benchmark runs first")
    ap.add_argument("--settle2d", action="store_true", help="settle2d at the same N too")
    a = ap.parse_args(argv)
    if a.reference:
        reference(a.reference, argv if argv is not None else sys.argv[1:])
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
    n_live = int((rig.sim.balls.alive == 1).sum())
    rate = n_live * steps / t_cyc
    print(f"cycles={a.cycles} time_per_cycle_s={per:.3f} steps_per_cycle={steps / a.cycles:.0f} "
          f"time_per_step_us={t_cyc / steps * 1e6:.1f}")
    print(f"case: {n_live} balls, ball_steps_per_s={rate:.3g}")
    if a.settle2d:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from engine_vs_lammps import run_ours
        r = run_ours(n_live, 20000)
        print(f"settle2d: {n_live} balls, ball_steps_per_s={r['bsps']:.3g}; "
              f"case / settle2d = {rate / r['bsps']:.2f}")
    print(f"minutes_per_1000_cycles={per * 1000 / 60:.2f}")
    return 0


def reference(src, argv):
    """Run SRC's own bench/case_benchmark.py with SRC's package (same arguments, minus the
    options it may not know), its output prefixed."""
    args, skip = [], False
    for x in argv:
        if skip:
            skip = False
        elif x == "--reference":
            skip = True
        elif not x.startswith(("--reference=", "--settle2d")):
            args.append(x)
    env = dict(os.environ, PYTHONPATH=str(Path(src).resolve() / "src"), NUMBA_NUM_THREADS="1")
    script = Path(src).resolve() / "bench" / "case_benchmark.py"
    out = subprocess.run([sys.executable, str(script)] + args, env=env, text=True,
                         capture_output=True, cwd=Path(__file__).resolve().parent.parent)
    for line in (out.stdout + out.stderr).splitlines():
        print(f"reference {src}: {line}")
    print(flush=True)


if __name__ == "__main__":
    sys.exit(main())
