"""Side-by-side check of the cyclic biaxial rig's quasi-static loading: is the frequency its
bounds set (rig/biaxial/inertial.py, with density scaling) slow enough? Does it change the
behaviours beyond the case-to-case scatter of a ten times slower reference?

    NUMBA_NUM_THREADS=1 python bench/biaxial_rate_check.py [--seeds 3] [--cycles 10]
        [--width 0.15] [--height 0.30] [--deviator-max 60] [--jobs 2]
        [--config config/config.yaml] [--library BPM.nc]
        [--reference KEY=VALUE,...] [--candidate KEY=VALUE,...]

Specimen: the rig parameters are the config's (rig.biaxial) with --width/--height; without
--library the small one of tests/rig (a synthetic library of 24 coarse stones, r0 = 8 mm,
and the tests' shortened assembly/consolidation: fill_area_ratio 0.9, relax_steps 2000,
consolidation_window_steps 1000), which runs in minutes; the issue's check takes box_test's
(--library results/bench_cache/config/box_test_bpm.nc, built by bench/biaxial_benchmark.py) at
0.15 x 0.30 and 0.30 x 0.60 m. --deviator-max applies to both settings; default 60 kPa,
the tests' value.

Each seed is assembled once; the same assembled specimen is then consolidated and loaded
with each setting (the setting's density scaling applies from consolidation on, as in a
real run): REFERENCE, ten times slower (both bounds of the quasi-static frequency,
quasi_static_inertial_number and quasi_static_lag, and cycle 0's first_loading_inertial_number, the
config's / 10; override with --reference), and CANDIDATE = the config's settings with the
--candidate overrides (e.g. quasi_static_inertial_number=3e-3). Prints per seed
and setting the axial strain after the first and after the last cycle, the volumetric
strain after the last, flat-joint elements broken since loading began (tension + shear:
the records are cumulative, so the last cycle's), the overshoot of the largest axial
stress above p + q_max, steps and seconds per cycle (the sinusoid's cycles 1...; the
consolidation and cycle 0, the bound-to-bound profile, are timed apart) and dt; a failed specimen (run.s.failure) is printed and
left out of the comparison. Then per behaviour the mean difference candidate - reference
(paired by seed) next to the standard deviation across seeds of the reference (the
case-to-case scatter), and the verdict

    within scatter  if |mean difference| <= 2 sd / sqrt(n)   (n seeds compared),
    beyond scatter  otherwise,

and the candidate's speed-up in seconds (and steps) per cycle. Never a test."""
import argparse
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import fields

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

# the reference: these settings of the config / 10 (computed: a typed-in reference once
# stayed at lag 0.025 when the config's went from 0.25 to 0.1, and was 4 x slower, not 10)
SLOWER = ("quasi_static_inertial_number", "quasi_static_lag", "first_loading_inertial_number")
SMALL = dict(fill_area_ratio=0.9, relax_steps=2000, consolidation_window_steps=1000,
             drop_max_steps=200000)
BEHAVIOURS = ("axial_strain_first", "axial_strain_last", "volumetric_strain_last",
              "elements_broken")
COLUMNS = BEHAVIOURS + ("overshoot_kPa", "steps_per_cycle", "s_per_cycle", "prep_s", "dt")
KPA = 1.0e3


def parse_overrides(text):
    out = {}
    for item in filter(None, (t.strip() for t in text.split(","))):
        key, value = item.split("=")
        out[key.strip()] = value.strip()
    return out


def apply(params, overrides, what):
    names = {f.name for f in fields(params)}
    for k, v in overrides.items():
        if k not in names:
            raise SystemExit(f"{what}: unknown biaxial rig key {k!r}")
        old = getattr(params, k)
        setattr(params, k, v if isinstance(old, str) else type(old)(float(v)))
    return params


def base_params(config, width, height, small):
    from ballaststudy.config import load_config
    from ballaststudy.rig.biaxial import BiaxialParams
    p = BiaxialParams.from_config(load_config(config).get("rig", {}))
    p.width_m, p.height_m = width, height
    for k, v in (SMALL if small else {}).items():
        setattr(p, k, v)
    return p


def assemble_one(library, params, seed, out):
    from ballaststudy.rig.biaxial import assemble_biaxial
    from ballaststudy.rig.library import load_library
    t = time.perf_counter()
    rig = assemble_biaxial(load_library(library), params, seed=seed)
    rig.save(out)
    return time.perf_counter() - t, int(rig.stone_balls().size), int(rig.layout.bonds_installed)


def load_one(assembled, overrides, deviator_max, cycles):
    """Consolidation, cycle 0 and ``cycles`` - 1 more cycles on a copy of the assembled
    specimen; the behaviours (or the failure / error)."""
    from ballaststudy.rig.biaxial import BiaxialRig, BiaxialRun
    rig = BiaxialRig.load(assembled)
    p = apply(rig.params, overrides, "--reference/--candidate")
    p.mode = "quasi_static"
    if deviator_max is not None:
        p.deviator_max_kPa = deviator_max
    try:
        run = BiaxialRun(rig, cycles=cycles)
        t0 = time.perf_counter()
        while run.s.phase in ("consolidation", "loading"):
            run.advance()
        t1, s1 = time.perf_counter(), rig.sim.step
        run.run()
        secs = time.perf_counter() - t1
    except RuntimeError as e:              # consolidation not reached, a cycle stalled...
        return dict(failure=f"error: {e}")
    c, rows, done = run.cyc, run.s.rows, len(run.s.rows)
    broken = rig.sim.n_breakages - run.s.log0
    out = dict(failure=run.s.failure, cycles_done=done, elements_broken=broken,
               prep_s=t1 - t0, dt=rig.sim.dt)
    if done:
        hi = (p.confining_pressure_kPa + p.deviator_max_kPa) * KPA
        out.update(axial_strain_first=rows[0]["axial_strain"],
                   axial_strain_last=rows[-1]["axial_strain"],
                   volumetric_strain_last=rows[-1]["volumetric_strain"],
                   overshoot_kPa=(max(c["axial_stress_max"]) - hi) / KPA,
                   steps_per_cycle=float(np.mean(c["cycle_steps"][1:])) if done > 1 else np.nan,
                   s_per_cycle=secs / (done - 1) if done > 1 else np.nan,
                   cyclic_steps=rig.sim.step - s1)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--width", type=float, default=0.15, help="specimen width [m]")
    ap.add_argument("--height", type=float, default=0.30, help="specimen height [m]")
    ap.add_argument("--deviator-max", type=float, default=60.0, metavar="KPA",
                    help="q_max of both settings (below the specimen's peak strength)")
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--library", help="a BPM.nc (default: the tests' small synthetic one)")
    ap.add_argument("--reference", help="rig overrides of the reference (default: the "
                    "config's " + ", ".join(SLOWER) + " / 10)")
    ap.add_argument("--candidate", default="", help="rig overrides of the candidate "
                    "(default none: the config's settings)")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    params = base_params(a.config, a.width, a.height, small=not a.library)
    a.reference = a.reference or ",".join(f"{k}={getattr(params, k) / 10:g}" for k in SLOWER)
    settings = {"reference": parse_overrides(a.reference),
                "candidate": parse_overrides(a.candidate)}
    for name, ov in settings.items():            # unknown keys fail before any run
        apply(base_params(a.config, a.width, a.height, False), ov, f"--{name}")
    seeds = list(range(1, a.seeds + 1))
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(a.jobs) as pool:
        library = a.library
        if not library:
            from ballaststudy.rig.library import synthetic_library
            library = os.path.join(tmp, "BPM.nc")
            synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3,
                              database="tiny").to_netcdf(library)
        paths = [os.path.join(tmp, f"seed{s}.nc") for s in seeds]
        for s, (t, nb, nf) in zip(seeds, pool.map(assemble_one, [library] * a.seeds,
                                                  [params] * a.seeds, seeds, paths)):
            print(f"seed {s}: assembled in {t:.0f} s, {nb} balls, {nf} bonds", flush=True)
        jobs = {(name, s): pool.submit(load_one, path, ov, a.deviator_max, a.cycles)
                for s, path in zip(seeds, paths) for name, ov in settings.items()}
        res = {k: f.result() for k, f in jobs.items()}
    p = params
    print(f"specimen {p.width_m:g} x {p.height_m:g} m, p = {p.confining_pressure_kPa:g} kPa, "
          f"q {p.deviator_min_kPa:g}-{a.deviator_max:g} kPa, {a.cycles} cycles, "
          f"library {a.library or 'small synthetic (tests/rig)'}")
    print(f"config:    quasi_static_inertial_number={p.quasi_static_inertial_number:g},"
          f"quasi_static_lag={p.quasi_static_lag:g},loading_dt_factor={p.loading_dt_factor:g}")
    print(f"reference: {a.reference}")
    print(f"candidate: config's settings{' + ' + a.candidate if a.candidate else ''}")
    print("setting   seed " + " ".join(f"{c:>22}" for c in COLUMNS))
    ok = []
    for s in seeds:
        good = True
        for name in settings:
            r = res[name, s]
            if r["failure"]:
                good = False
                print(f"{name:9} {s:4} FAILED after {r.get('cycles_done', 0)} cycles: {r['failure']}")
            if r.get("cycles_done"):
                print(f"{name:9} {s:4} " + " ".join(f"{r[c]:22.6g}" for c in COLUMNS))
        if good:
            ok.append(s)
    n = len(ok)
    if n < len(seeds):
        print(f"compared: seeds {ok} (a failed specimen is left out)")
    if n == 0:
        print("nothing to compare")
        return 1
    for c in BEHAVIOURS:
        refv = np.array([res["reference", s][c] for s in ok], float)
        cand = np.array([res["candidate", s][c] for s in ok], float)
        d = np.mean(cand - refv)
        sd = refv.std(ddof=1) if n > 1 else float("nan")
        bound = 2 * sd / np.sqrt(n)
        verdict = ("n/a (needs 2 seeds)" if n < 2 else
                   "within scatter" if abs(d) <= bound else "beyond scatter")
        print(f"{c}: reference mean {refv.mean():.6g}, candidate mean {cand.mean():.6g}, "
              f"mean difference {d:+.6g}, sd across seeds (reference) {sd:.6g}, "
              f"2 sd/sqrt(n) {bound:.3g}: {verdict}")
    for c in ("s_per_cycle", "steps_per_cycle"):
        refv = np.array([res["reference", s][c] for s in ok])
        cand = np.array([res["candidate", s][c] for s in ok])
        print(f"{c}: reference {refv.mean():.4g}, candidate {cand.mean():.4g}, "
              f"speed-up x{refv.mean() / cand.mean():.2f}")
    print(f"wall time {time.perf_counter() - t_all:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
