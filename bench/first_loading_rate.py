"""Is cycle 0 (the bound-to-bound profile of the first loading) quasi-static, and is what
its speed changes a rate effect or the chaos of a granular specimen's first loading?

    NUMBA_NUM_THREADS=1 python bench/first_loading_rate.py [--seeds 3] [--cycles 20]
        [--inertial-numbers 1.6e-3 1.6e-4 1.6e-5] [--twin 1.01] [--width 0.15] [--height 0.30]
        [--deviator-max 80] [--library BPM.nc] [--config config/config.yaml] [--jobs 2]

Each seed is assembled once (as bench/biaxial_rate_check.py does, whose helpers it uses);
the same specimen is then consolidated and loaded, quasi-static, with cycle 0's platen
speed (first_loading_inertial_number) at each of --inertial-numbers, and at each also at
--twin x it (a 1 % change: no rate effect can act, so the
twins' difference is the path's sensitivity to any small change, the chaos of the first
loading). The sinusoid's cycles 1... are the config's. Prints per seed and I the
profile's platen speed v = (I / (d sqrt(rho / p))) H (rig.biaxial.inertial's d and rho,
density scaling included), the axial strain after cycle 0 and after the last cycle, the
volumetric strain after the last, flat-joint elements broken and cycle 0's seconds; then
per behaviour the mean |difference| over seeds between neighbouring I beside the
mean |difference| between twins: a rate effect is a difference between inertial numbers well above
the twins'; where the two are alike the speed changes the path no more than a 1 % nudge.
Never a test."""
import argparse
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
from biaxial_rate_check import assemble_one, base_params, load_one  # noqa: E402

BEHAVIOURS = ("axial_strain_first", "axial_strain_last", "volumetric_strain_last",
              "elements_broken")


def speed_per_inertial_number(assembled):
    """Cycle 0's platen speed [m/s] at I = 1 on this specimen (at p)."""
    from ballaststudy.rig.biaxial import BiaxialRig
    from ballaststudy.rig.biaxial.inertial import profile_speed
    rig = BiaxialRig.load(assembled)
    p = rig.params
    rig.sim.set_density_scaling(p.loading_dt_factor * rig.sim.dt)
    return profile_speed(rig, 1.0, p.confining_pressure_kPa * 1e3)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=20)
    ap.add_argument("--inertial-numbers", type=float, nargs="+", default=[1.6e-3, 1.6e-4, 1.6e-5],
                    help="cycle 0's first_loading_inertial_number, fastest first")
    ap.add_argument("--twin", type=float, default=1.01, help="the twin's speed factor (0: no twins)")
    ap.add_argument("--width", type=float, default=0.15)
    ap.add_argument("--height", type=float, default=0.30)
    ap.add_argument("--deviator-max", type=float, default=80.0, metavar="KPA")
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--library", default="results/bench_cache/config/box_test_bpm.nc")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    params = base_params(a.config, a.width, a.height, small=False)
    settings = [(v, t) for v in a.inertial_numbers for t in ((1.0, a.twin) if a.twin else (1.0,))]
    seeds = list(range(1, a.seeds + 1))
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(a.jobs) as pool:
        paths = [os.path.join(tmp, f"seed{s}.nc") for s in seeds]
        for s, (t, nb, nf) in zip(seeds, pool.map(assemble_one, [a.library] * a.seeds,
                                                  [params] * a.seeds, seeds, paths)):
            print(f"seed {s}: assembled in {t:.0f} s, {nb} balls, {nf} bonds", flush=True)
        speed = {s: speed_per_inertial_number(path) for s, path in zip(seeds, paths)}
        jobs = {}
        for v, t in settings:
            ov = dict(first_loading_inertial_number=str(v * t))
            for s, path in zip(seeds, paths):
                jobs[v, t, s] = pool.submit(load_one, path, ov, a.deviator_max, a.cycles)
        res = {k: f.result() for k, f in jobs.items()}
    p = params
    print(f"specimen {p.width_m:g} x {p.height_m:g} m, p = {p.confining_pressure_kPa:g} kPa, "
          f"q {p.deviator_min_kPa:g}-{a.deviator_max:g} kPa, {a.cycles} cycles (cycle 0 the "
          f"profile), library {a.library}")
    cols = BEHAVIOURS + ("prep_s",)
    print("inertial_number seed  speed_m_s " + " ".join(f"{c:>22}" for c in cols))
    for v, t in settings:
        for s in seeds:
            r = res[v, t, s]
            head = f"{v * t:<15.4g} {s:4} {speed[s] * v * t:10.3g} "
            if r["failure"]:
                print(head + f"FAILED after {r.get('cycles_done', 0)} cycles: {r['failure']}")
            else:
                print(head + " ".join(f"{r[c]:22.6g}" for c in cols))
    ok = [s for s in seeds if not any(res[v, t, s]["failure"] for v, t in settings)]
    if not ok:
        print("nothing to compare")
        return 1
    print(f"mean |difference| over seeds {ok} (a seed that failed at any speed is left out)")
    for c in BEHAVIOURS:
        val = {(v, t): np.array([res[v, t, s][c] for s in ok], float) for v, t in settings}
        twins = [np.mean(np.abs(val[v, a.twin] - val[v, 1.0])) if a.twin else np.nan
                 for v in a.inertial_numbers]
        steps = [np.mean(np.abs(val[v1, 1.0] - val[v0, 1.0]))
                 for v0, v1 in zip(a.inertial_numbers, a.inertial_numbers[1:])]
        levels = a.inertial_numbers
        sd = np.mean([val[v, 1.0].std(ddof=1) for v in levels]) if len(ok) > 1 else np.nan
        print(f"{c}: twins (x{a.twin:g}) " + ", ".join(f"{v:g}: {d:.3g}" for v, d in zip(levels, twins))
              + " | I steps " + ", ".join(f"{v0:g}->{v1:g}: {d:.3g}" for (v0, v1), d
                                          in zip(zip(levels, levels[1:]), steps))
              + f" | sd across seeds {sd:.3g}")
    print(f"wall time {time.perf_counter() - t_all:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
