"""Cyclic biaxial case benchmark: the default specimen of the config at its resolution.

    NUMBA_NUM_THREADS=1 python bench/biaxial_benchmark.py [--cycles 10]
        [--config config/config.yaml] [--library BPM.nc] [--seed 1]
        [--modes quasi_static real_time] [--frequency 20] [--deviator-max KPA]
        [--width 0.3 --height 0.6] [--membrane-segments N]

Uses the BPM library given, else box_test's at the config's resolution (built once and
cached in results/bench_cache, like bench/case_benchmark.py). Prints assembly and
consolidation times, what sets the timestep (the limiting ball, its springs, the per-ball
dt_crit's percentiles: Simulation.timestep_limit), then per loading mode (quasi-static; real-time at the frequency f,
which it states) balls, bonds, steps per cycle, time per step and
``minutes_per_1000_cycles=<x>`` extrapolated from the cyclic phase. Both modes start from
the same assembled specimen; --width/--height/--membrane-segments change the config's
specimen (e.g. measured_sim's 0.15 x 0.30 m, or a membrane). Last, settle2d's ball-steps/s
(bench/engine_vs_lammps.py, N = --settle2d-n) in the same process: the engine's rate on
this machine now, beside the rig's. Never a test."""
import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--library", help="a BPM.nc (default: build box_test's)")
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--modes", nargs="+", default=["quasi_static", "real_time"])
    ap.add_argument("--frequency", type=float, help="f of the real-time mode [Hz] (config's)")
    ap.add_argument("--deviator-max", type=float, metavar="KPA",
                    help="q_max (config's); below the specimen's peak strength, else it fails")
    ap.add_argument("--width", type=float, help="specimen width [m] (config's)")
    ap.add_argument("--height", type=float, help="specimen height [m] (config's)")
    ap.add_argument("--membrane-segments", type=int, help="1 rigid sides, n > 1 a membrane (config's)")
    ap.add_argument("--settle2d-n", type=int, default=5000, help="balls of the settle2d reference (0: none)")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from case_benchmark import box_test_library
    from engine_vs_lammps import run_ours

    from ballaststudy.config import load_config
    from ballaststudy.rig.biaxial import BiaxialParams, BiaxialRig, BiaxialRun, assemble_biaxial
    from ballaststudy.rig.library import load_library
    params = BiaxialParams.from_config(load_config(a.config).get("rig", {}))
    for key, value in (("width_m", a.width), ("height_m", a.height),
                       ("membrane_segments", a.membrane_segments)):
        if value is not None:
            setattr(params, key, value)
    lib = load_library(a.library or box_test_library(a.config))
    t0 = time.perf_counter()
    rig = assemble_biaxial(lib, params, seed=a.seed)
    print(f"assembly: {time.perf_counter() - t0:.1f} s, stages {rig.layout.stage_steps}")
    n_balls = int((rig.sim.balls.alive == 1).sum())
    print(f"specimen {params.width_m:g} x {params.height_m:g} m, membrane_segments="
          f"{params.membrane_segments}: balls={n_balls} "
          f"bonds={rig.layout.bonds_installed} dt={rig.sim.dt:.3g} s")
    lim = rig.sim.timestep_limit()
    print(f"timestep: dt_crit {lim['dt_crit']:.3g} s set by ball {lim['ball']} (radius "
          f"{lim['radius'] * 1e3:.2f} mm, mass {lim['mass'] * 1e3:.1f} g per m of thickness, "
          f"{lim['bonds']} flat joints, by {lim['springs']}); per-ball dt_crit percentiles "
          f"1/10/50: {', '.join(f'{v:.3g}' for v in lim['percentiles'])} s")
    assembled = Path(tempfile.mkdtemp()) / "assembled.nc"
    rig.save(assembled)
    for mode in a.modes:
        rig = BiaxialRig.load(assembled)
        rig.params.mode = mode
        if a.frequency:
            rig.params.frequency_Hz = a.frequency
        if a.deviator_max:
            rig.params.deviator_max_kPa = a.deviator_max
        state = f" f={rig.params.frequency_Hz:g} Hz" if mode == "real_time" else ""
        run = BiaxialRun(rig, cycles=a.cycles)
        t1, s1 = time.perf_counter(), rig.sim.step
        while run.s.phase in ("consolidation", "loading"):
            run.advance()
        print(f"[{mode}{state}] consolidation + first loading: {time.perf_counter() - t1:.1f} s, "
              f"{rig.sim.step - s1} steps, windows {len(run.s.window_means)}")
        t2, s2, rows0 = time.perf_counter(), rig.sim.step, len(run.s.rows)
        run.run()
        t = time.perf_counter() - t2
        steps, done = rig.sim.step - s2, len(run.s.rows) - rows0     # the cycles timed
        if run.s.failure:
            print(f"[{mode}{state}] q_max {rig.params.deviator_max_kPa:g} kPa: {run.s.failure} "
                  f"(after {done} cycles; give --deviator-max below the peak)")
        if not done:
            print(f"[{mode}{state}] minutes_per_1000_cycles=n/a (no cycle completed)")
            continue
        per = t / done
        print(f"[{mode}{state}] balls={n_balls} bonds={rig.layout.bonds_installed} q_max="
              f"{rig.params.deviator_max_kPa:g} kPa cycles={done} steps_per_cycle={steps / done:.0f} dt={rig.sim.dt:.3g} s "
              f"time_per_step_us={t / steps * 1e6:.1f} ball_steps_per_s={n_balls * steps / t:.3g}")
        print(f"[{mode}{state}] axial strain after each cycle: "
              f"{[round(r['axial_strain'], 5) for r in run.s.rows]}")
        hi = (rig.params.confining_pressure_kPa + rig.params.deviator_max_kPa) * 1e3
        lo = (rig.params.confining_pressure_kPa + rig.params.deviator_min_kPa) * 1e3
        c = run.cyc
        print(f"[{mode}{state}] per cycle: sigma_1 max - (p + q_max) [kPa] "
              f"{[round((v - hi) / 1e3, 2) for v in c['axial_stress_max']]}, sigma_1 min - "
              f"(p + q_min) [kPa] {[round((v - lo) / 1e3, 2) for v in c['axial_stress_min']]}, "
              f"steps {[int(v) for v in c['cycle_steps']]}")
        print(f"[{mode}{state}] per cycle: frequency [Hz] "
              f"{[round(v, 2) for v in c['loading_frequency']]}, inertia added "
              f"{[round(v, 4) for v in c['inertia_added']]}")
        print(f"[{mode}{state}] minutes_per_1000_cycles={per * 1000 / 60:.2f}")
    if a.settle2d_n:
        ref = run_ours(a.settle2d_n, 20000)
        print(f"settle2d N={a.settle2d_n}: ball_steps_per_s={ref['bsps']:.3g} (same process, after the rig)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
