"""Bonded against rigid stones on the same assembled specimens, in one process.

    NUMBA_NUM_THREADS=1 python bench/stone_models.py SPEC [SPEC ...] [--quick]
        [--config config/thesis.yaml] [--warm 1] [--cycles 10]

SPEC = [LABEL=]ASSEMBLED.nc[@MODE] (MODE of a biaxial specimen: quasi_static, or
real_time:F for the real-time loading at F Hz; default the config's). Each specimen is
loaded under the config's rig parameters once per stone model (ballaststudy.stones): the
first ``--warm`` cycles (the static or consolidation phase and the first loading: numba's
compilation and the assembly's seating are not what a long run pays) are run and not
timed, then ``--cycles`` cycles are timed in process CPU time. Both models run at the
settings a user runs: the config's density scaling (rig.*.loading.loading_dt_factor, or
real-time's realtime_added_inertia_max) for both, balls and clumps alike. A biaxial
specimen's first loading (cycle 0, untimed) runs at ``--first-loading-inertial-number``
(default 1e-3, not the config's 1.5e-5: that one alone is ~16 M bonded steps on a full
0.30 x 0.60 m specimen); the timed cycles run at the config's settings.

Per row and model: core-seconds per cycle (median of the timed cycles), steps per cycle,
dt and what limits it (Simulation.timestep_limit: the body, translation or rotation), the
bodies that move (free balls + free clumps), the contacts carrying force at the end; then
``min_per_1000=<x>`` (the median cycle x 1000) and, LAST on each row's line,
``speedup=<x>`` = bonded core-s per cycle / rigid's, measured in this run. ``--quick``:
one warm cycle and three timed ones (a few minutes a row on one core). Never a test."""
import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from ballaststudy.config import load_config  # noqa: E402
from ballaststudy.inputs import open_netcdf  # noqa: E402
from ballaststudy.rig.kinds import kind_of, params_from_config, rig_classes  # noqa: E402
from ballaststudy.stones import STONE_MODELS  # noqa: E402


def parse_spec(text):
    label, _, rest = text.rpartition("=")
    path, _, mode = rest.partition("@")
    return label or os.path.basename(os.path.dirname(path)) or path, path, mode


def loaded_rig(path, model, cfg, mode, first_loading=None, deviator_max=None):
    ds = open_netcdf(path, "assembled")
    kind = kind_of(ds)
    rig_class, run_class, _ = rig_classes(kind)
    rig = rig_class.from_dataset(ds, path)
    rig.params = params_from_config(kind, cfg.get("rig", {}))
    if first_loading is not None and hasattr(rig.params, "first_loading_inertial_number"):
        rig.params.first_loading_inertial_number = first_loading
    if deviator_max is not None and hasattr(rig.params, "deviator_max_kPa"):
        rig.params.deviator_max_kPa = deviator_max
    if mode:
        name, _, f = mode.partition(":")
        rig.params.mode = name
        if f:
            rig.params.frequency_Hz = float(f)
    rig.use_stone_model(model)
    return rig, run_class


def measure(path, model, cfg, mode, warm, cycles, first_loading=None, deviator_max=None):
    """Time ``cycles`` cycles after ``warm`` untimed ones: dict of the row's figures."""
    rig, run_class = loaded_rig(path, model, cfg, mode, first_loading, deviator_max)
    run = run_class(rig, warm + cycles, checkpoint=None)
    stamps = {}

    def progress(phase, cycle):
        if cycle not in stamps:
            stamps[cycle] = (time.process_time(), rig.sim.step)

    run.run(progress=progress)
    sim = rig.sim
    ends = [stamps[c] for c in range(warm, warm + cycles + 1) if c in stamps]
    per_cycle = np.diff([t for t, _ in ends])
    steps = np.diff([s for _, s in ends])
    lim = sim.timestep_limit()
    b, c = sim.balls, sim.clumps
    bodies = int(((b.alive == 1) & (b.clump < 0)).sum() + (c.held == 0).sum())
    return dict(core_s=float(np.median(per_cycle)) if len(per_cycle) else float("nan"),
                steps=float(np.median(steps)) if len(steps) else float("nan"),
                dt=sim.dt, limit=f"{lim['body']} {lim['springs']} (dt_crit {lim['dt_crit']:.3g} s)",
                bodies=bodies, contacts=int(len(sim.contact_list()["i"])),
                added=sim.added_inertia(), failure=getattr(run.s, "failure", ""),
                cycles_timed=len(per_cycle))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("specimens", nargs="+", metavar="SPEC")
    ap.add_argument("--config", default="config/thesis.yaml")
    ap.add_argument("--warm", type=int, default=1)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--quick", action="store_true", help="1 warm + 3 timed cycles a row")
    ap.add_argument("--models", nargs="+", choices=STONE_MODELS, default=list(STONE_MODELS),
                    help="the rows to run (speedup only with both)")
    ap.add_argument("--first-loading-inertial-number", type=float, default=1e-3,
                    help="biaxial: cycle 0's first loading (untimed; the config's 1.5e-5 "
                    "takes ~16 M bonded steps on a full specimen); 0: the config's")
    ap.add_argument("--deviator-max-kPa", type=float, help="biaxial: q_max of the cycles "
                    "instead of the config's (a bound both models' specimens carry)")
    a = ap.parse_args(argv)
    warm, cycles = (1, 3) if a.quick else (a.warm, a.cycles)
    cfg = load_config(a.config)
    print(f"config {a.config}; {warm} warm + {cycles} timed cycles a row; process CPU time, "
          f"NUMBA_NUM_THREADS={os.environ['NUMBA_NUM_THREADS']}; biaxial: first loading at I = "
          f"{a.first_loading_inertial_number or '(config)'}, q_max = {a.deviator_max_kPa or '(config)'} kPa")
    for spec in a.specimens:
        label, path, mode = parse_spec(spec)
        first = a.first_loading_inertial_number or None
        rows = {m: measure(path, m, cfg, mode, warm, cycles, first, a.deviator_max_kPa)
                for m in a.models}
        for m, r in rows.items():
            print(f"  {label} {m:6s}: {r['core_s']:.3f} core-s/cycle ({r['cycles_timed']} timed), "
                  f"{r['steps']:.0f} steps/cycle, dt {r['dt']:.3g} s [{r['limit']}], inertia added "
                  f"{r['added']:.3f}, bodies {r['bodies']}, contacts {r['contacts']}"
                  + (f", FAILED: {r['failure']}" if r["failure"] else ""))
        if len(rows) < 2:
            continue
        bonded, rigid = rows["bonded"], rows["rigid"]
        print(f"{label}{'@' + mode if mode else ''}: bonded_min_per_1000={bonded['core_s'] * 1000 / 60:.2f} "
              f"rigid_min_per_1000={rigid['core_s'] * 1000 / 60:.2f} "
              f"speedup={bonded['core_s'] / rigid['core_s']:.2f}", flush=True)


if __name__ == "__main__":
    main()
