"""Side-by-side check of the loading settings: does a faster cyclic loading (speed profile,
density scaling) change settlement and breakage beyond the case-to-case scatter?

    NUMBA_NUM_THREADS=1 python bench/loading_rate_check.py [--seeds 3] [--cycles 30]
        [--config config/config.yaml] [--library BPM.nc] [--jobs 2]
        [--reference KEY=VALUE,...] [--candidate NAME:KEY=VALUE,... ...]

Each seed is assembled once (box_test library, as bench/case_benchmark.py); the same
assembled state is then loaded with the conservative REFERENCE loading settings (slow
speed profile over the whole range, no density scaling; override with --reference), with
the config's settings and with each ``--candidate`` (the config's settings with rig
overrides, e.g. ``dt4:loading_dt_factor=4``). Prints per seed and setting the final
settlement, the displacement at peak, flat-joint elements broken, steps and seconds per
cycle; then per setting the mean difference setting - reference of each behaviour next to
the standard deviation across seeds of the reference (the case-to-case scatter). Never a
test."""
import argparse
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from case_benchmark import box_test_library  # noqa: E402

REFERENCE = "cyclic_v_max_m_s=0.05,cyclic_v_min_m_s=0.005,cyclic_braking_fraction=1,loading_dt_factor=1"
BEHAVIOURS = ("settlement", "displacement_at_peak", "elements_broken", "breakage_rate")


def parse_overrides(text):
    out = {}
    for item in filter(None, text.split(",")):
        key, value = item.split("=")
        out[key.strip()] = float(value)
    return out


def params_from(config, overrides):
    from ballaststudy.config import load_config
    from ballaststudy.rig.params import RigParams
    p = RigParams.from_config(load_config(config).get("rig", {}))
    for k, v in overrides.items():
        if not hasattr(p, k):
            raise SystemExit(f"--reference: unknown rig key {k!r}")
        setattr(p, k, type(getattr(p, k))(v))
    return p


def assemble_one(library, config, seed, out):
    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.library import load_library
    t = time.perf_counter()
    rig = assemble(load_library(library), params_from(config, {}), seed=seed)
    rig.save(out)
    return time.perf_counter() - t


def load_one(assembled, config, overrides, cycles):
    """Static + ``cycles`` cyclic on a copy of the assembled state; the behaviours."""
    from ballaststudy.rig.box import BoxRig
    from ballaststudy.rig.loading import LoadingRun
    rig = BoxRig.load(assembled)
    rig.params = params_from(config, overrides)
    run = LoadingRun(rig, cycles=cycles)
    while run.s.phase in ("static", "unload"):
        run.advance()
    t, s0 = time.perf_counter(), rig.sim.step
    run.run()
    secs = time.perf_counter() - t
    last = run.s.rows[-1]
    broken = run.cyc["elements_broken_tension"][-1] + run.cyc["elements_broken_shear"][-1]
    fmax = max(run.cyc["force_max"][1:] or run.cyc["force_max"])
    return dict(settlement=last["settlement"], displacement_at_peak=last["displacement_at_peak"],
                elements_broken=broken, breakage_rate=last["breakage_rate"],
                steps_per_cycle=(rig.sim.step - s0) / cycles, s_per_cycle=secs / cycles,
                overshoot_N=fmax - rig.params.cyclic_max_kN * 1e3, dt=rig.sim.dt)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=30)
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--library", help="a BPM.nc (default: build box_test's)")
    ap.add_argument("--reference", default=REFERENCE, help="rig overrides of the reference")
    ap.add_argument("--candidate", nargs="*", default=[],
                    help="further settings NAME:KEY=VALUE,... (config + overrides)")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    ref = parse_overrides(a.reference)
    library = a.library or box_test_library(a.config)
    settings = {"reference": ref, "config": {}}
    for c in a.candidate:
        name, _, text = c.partition(":")
        settings[name] = parse_overrides(text)
    with tempfile.TemporaryDirectory() as tmp, ProcessPoolExecutor(a.jobs) as pool:
        paths = [os.path.join(tmp, f"seed{s}.nc") for s in range(1, a.seeds + 1)]
        for s, t in zip(range(1, a.seeds + 1), pool.map(assemble_one, [library] * a.seeds,
                                                         [a.config] * a.seeds,
                                                         range(1, a.seeds + 1), paths)):
            print(f"seed {s}: assembled in {t:.0f} s")
        jobs = {(name, s): pool.submit(load_one, path, a.config, ov, a.cycles)
                for s, path in enumerate(paths, 1) for name, ov in settings.items()}
        res = {k: f.result() for k, f in jobs.items()}
    print(f"reference: {a.reference}")
    cols = BEHAVIOURS + ("steps_per_cycle", "s_per_cycle", "overshoot_N", "dt")
    print("setting   seed " + " ".join(f"{c:>20}" for c in cols))
    for (name, s), r in sorted(res.items()):
        print(f"{name:9} {s:4} " + " ".join(f"{r[c]:20.6g}" for c in cols))
    seeds = range(1, a.seeds + 1)
    for name in [n for n in settings if n != "reference"]:
        for c in BEHAVIOURS + ("steps_per_cycle", "s_per_cycle"):
            refv = np.array([res["reference", s][c] for s in seeds])
            cand = np.array([res[name, s][c] for s in seeds])
            print(f"{name} {c}: reference mean {refv.mean():.6g}, {name} mean "
                  f"{cand.mean():.6g}, mean difference {np.mean(cand - refv):+.6g}, "
                  f"case-to-case std (reference) "
                  f"{refv.std(ddof=1) if a.seeds > 1 else float('nan'):.6g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
