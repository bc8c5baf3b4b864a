"""Batched GPU engine on the rigs: B cases' cycles as one batch (rig/batched.py), beside
one case's on the CPU engine in the same run.

    python bench/gpu_rigs.py [--batch 100] [--width 0.3 --height 0.6] [--cycles 2 (>= 2)]
        [--frequency 20] [--deviator-max 80] [--first-loading-inertial-number 1.35e-4]
        [--check-every 100] [--config config/config.yaml] [--library BPM.nc]
    python bench/gpu_rigs.py --rig box --batch 160 --config config/thesis.yaml --cycles 5

Biaxial (default): one specimen of box_test's library at the config's resolution
(bench/case_benchmark.py builds and caches the library), assembled on the CPU (seed 1) and
copied B times. Every copy
consolidates and loads first (cycle 0) at --first-loading-inertial-number (default the
tests' fast rate, tests/biaxial_fast.py: the config's physics-bound 1.5e-5 takes ten times
the steps, and the cycles' cost does not depend on it), then runs --cycles real-time cycles
at --frequency between the config's q_min and --deviator-max (below the small specimens'
strength). Prints the wall time of cycle 0 and of the cycles on the batch, the engine runs
per case and cycle (each a halt the host reacts to), the axial strain after each cycle of
copy 0, ``gpu_batch_minutes_per_1000_cycles=`` (the whole batch) and the same for one copy
on the CPU engine (one thread, a subprocess running beside the GPU part:
``cpu_one_case_minutes_per_1000_cycles=``). Needs a CUDA GPU (NUMBA_ENABLE_CUDASIM=1: a dry
run, with tiny settings). ``--rig box``: the box test's case 0 of box_test at the config's
resolution (thesis.yaml: the thesis-scale study's) copied B times, its static loads and
cycle 0, then --cycles cycles (the study's 160 cases x 1000 cycles: minutes per 1000
cycles of B = 160).

For a lent GPU's minutes (bench/gpu_lease.sh): --assemble-only and --cycle0-only prepare
the specimen and its run after cycle 0 on the CPU, --assembled/--resume copy them there.
Cycle 1 is the warm-up (numba's and the GPU's compiles fall in it); the rates are of the
cycles after it (--budget: as many as fit, at least one). Each GPU drive prints where its
time went (the hosts' code, starts, device stepping, exports, halts); --kernels adds a
cycle with each kernel timed alone. Never a test.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def arguments(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rig", choices=["biaxial", "box"], default="biaxial")
    ap.add_argument("--batch", type=int, default=100)
    ap.add_argument("--width", type=float, default=0.3)
    ap.add_argument("--height", type=float, default=0.6)
    ap.add_argument("--cycles", type=int, default=2)
    ap.add_argument("--frequency", type=float, default=20.0)
    ap.add_argument("--deviator-max", type=float, default=80.0, metavar="KPA")
    ap.add_argument("--first-loading-inertial-number", type=float, default=1.35e-4)
    ap.add_argument("--check-every", type=int, default=100)
    ap.add_argument("--cycle0-only", metavar="OUT",
                    help="run one copy's cycle 0 on the CPU, save its checkpoint to OUT and "
                    "stop (the GPU run's --resume)")
    ap.add_argument("--resume", metavar="NPZ",
                    help="copies of the run saved by --cycle0-only (cycle 0 not timed)")
    ap.add_argument("--kernels", action="store_true",
                    help="then one more cycle with each kernel timed alone")
    ap.add_argument("--budget", type=float, default=float("inf"), metavar="S",
                    help="no further cycle once S seconds are spent (each of GPU and CPU)")
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--library", help="a BPM.nc (default: box_test's, built once)")
    ap.add_argument("--assembled", help="an assembled specimen (.nc) to copy instead of "
                    "assembling one here")
    ap.add_argument("--assemble-only", metavar="OUT",
                    help="assemble the specimen on the CPU, save it to OUT and stop (no GPU "
                    "needed: the GPU run's --assembled)")
    ap.add_argument("--specimen", help=argparse.SUPPRESS)      # the CPU child's
    a = ap.parse_args(argv)
    if a.cycles < 2:
        ap.error("--cycles: at least 2 (cycle 1 is the warm-up, the rate is of those after)")
    return a


def assembled(a, path=None):
    if a.assembled:
        return Path(a.assembled)
    from case_benchmark import box_test_library

    from ballaststudy.config import load_config
    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.biaxial import assemble_biaxial
    from ballaststudy.rig.kinds import params_from_config
    from ballaststudy.rig.library import load_library
    params = params_from_config(a.rig, load_config(a.config).get("rig", {}))
    lib = load_library(a.library or box_test_library(a.config))
    t = time.perf_counter()
    if a.rig == "box":
        rig = assemble(lib, params, seed=1)
    else:
        params.width_m, params.height_m = a.width, a.height
        rig = assemble_biaxial(lib, params, seed=1)
    path = Path(path or Path(tempfile.mkdtemp()) / "assembled.nc")
    rig.save(path)
    print(f"assembled on the CPU in {time.perf_counter() - t:.0f} s: "
          f"{int(rig.sim.balls.alive.sum())} balls, {rig.layout.bonds_installed} bonds", flush=True)
    return path


def copies(path, a, n):
    """n runs of the case at path (biaxial: real time), or of --resume's saved run: cycle
    0, --cycles and a spare (--kernels' cycle); each counts its engine runs
    (``run.engine_runs``)."""
    from ballaststudy.rig.kinds import rig_classes
    rig_class, run_class, _ = rig_classes(a.rig)
    out = []
    for _ in range(n):
        if a.resume:
            run = run_class.from_checkpoint(a.resume, cycles=2 + a.cycles)
            run.checkpoint = None               # (copies do not write it back)
        else:
            rig = rig_class.load(path)
            p = rig.params
            if a.rig == "biaxial":
                p.mode, p.frequency_Hz = "real_time", a.frequency
                p.deviator_max_kPa = a.deviator_max
                p.first_loading_inertial_number = a.first_loading_inertial_number
            run = run_class(rig, cycles=2 + a.cycles)    # a spare: breakdown's
        run.engine_runs = 0
        advance = run.advance

        def counted(max_steps=None, run=run, advance=advance):
            run.engine_runs += 1
            return advance(max_steps)
        run.advance = counted
        out.append(run)
    return out


def timed(runs, drive, label, cycles, budget_s, clock=None):
    """(s to the end of cycle 0, s of the cycles timed, their number, engine runs in
    those). Cycle 0 in one drive, cycle 1 in another (the warm-up: numba's and the GPU's
    compiles fall in it; its time says how many more of --cycles fit in budget_s, at least
    one), the rest in one drive: the rate is of that last drive, whose batch is made
    once, as a calibration's is."""
    t0 = time.perf_counter()
    if runs[0].s.cycle == 0:
        drive(runs, lambda r: r.run(stop_after=1))
        print(f"[{label}] cycle 0: {time.perf_counter() - t0:.1f} s{split(clock)}", flush=True)
    else:
        print(f"[{label}] cycle 0: done, from --resume", flush=True)
    t1 = time.perf_counter()
    drive(runs, lambda r: r.run(stop_after=1))
    t2 = time.perf_counter()
    print(f"[{label}] cycle 1 (warm-up, compiles included): {t2 - t1:.1f} s{split(clock)}",
          flush=True)
    e2 = sum(r.engine_runs for r in runs)
    more = max(1, min(cycles - 1, int((budget_s - (t2 - t0)) / (t2 - t1))))
    drive(runs, lambda r: r.run(stop_after=more))
    t3 = time.perf_counter()
    print(f"[{label}] cycles 2-{1 + more}: {t3 - t2:.1f} s{split(clock)}", flush=True)
    return t1 - t0, t3 - t2, more, sum(r.engine_runs for r in runs) - e2


def split(clock):
    """'; hosts 1.2 s, ...' of the batch's drive since the last call (then cleared)."""
    if not clock:
        return ""
    out = "; " + ", ".join(f"{k} {v:.2f} s" for k, v in clock.items() if not k.endswith("_n"))
    out += f"; {clock.get('advance_n', 0)} advances, {clock.get('export_n', 0)} halts"
    clock.clear()
    return out


def one_by_one(runs, job):
    for r in runs:
        job(r)


def report(label, runs, a, t0, tc, n_cycles, engine_runs):
    failed = [r.s.failure for r in runs if getattr(r.s, "failure", None)]
    print(f"[{label}] B={len(runs)}: cycle 0 {t0:.1f} s; {n_cycles} cycles {tc:.1f} s; "
          f"engine runs per case and cycle {engine_runs / (len(runs) * n_cycles):.0f}; "
          f"failed {len(failed)}{': ' + failed[0] if failed else ''}", flush=True)
    key = "axial_strain" if a.rig == "biaxial" else "settlement"
    values = ", ".join(f"{r.get(key, float('nan')):.4g}" for r in runs[0].s.rows)
    print(f"[{label}] copy 0 {key} after each cycle: {values}", flush=True)
    return tc / n_cycles * 1000 / 60


def breakdown(runs, a):
    """One more cycle with each kernel timed alone (the device synchronised around each
    launch, so slower than the cycles above): where the device's time goes."""
    from ballaststudy.rig.batched import run_batched
    kernels, clock = {}, {}
    t = time.perf_counter()
    run_batched(runs, lambda r: r.run(stop_after=1), check_every=a.check_every, clock=clock,
                kernels=kernels)
    print(f"[gpu] one cycle, each kernel synchronised: {time.perf_counter() - t:.1f} s"
          f"{split(clock)}; kernels: "
          + ", ".join(f"{k} {v:.2f} s" for k, v in sorted(kernels.items(), key=lambda kv: -kv[1])),
          flush=True)


def main(argv=None):
    a = arguments(argv)
    if a.specimen:                     # the CPU child: one copy on the CPU engine
        runs = copies(a.specimen, a, 1)
        per = report("cpu", runs, a, *timed(runs, one_by_one, "cpu", a.cycles, a.budget))
        print("CPU_RESULT " + json.dumps(dict(minutes=per)), flush=True)
        return 0
    if a.assemble_only:
        assembled(a, a.assemble_only)
        return 0
    if a.cycle0_only:
        t = time.perf_counter()
        (run,) = copies(assembled(a), a, 1)
        run.run(stop_after=1)
        run.save_checkpoint(a.cycle0_only)
        print(f"cycle 0 on the CPU in {time.perf_counter() - t:.0f} s: {a.cycle0_only}")
        return 0
    from ballaststudy.dem.gpu import cuda_available
    from ballaststudy.rig.batched import run_batched
    if not cuda_available():
        print("gpu_rigs.py: no CUDA GPU visible to numba", file=sys.stderr)
        return 2
    path = assembled(a)
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    child = subprocess.Popen([sys.executable, __file__, *(argv or sys.argv[1:]), "--specimen",
                              str(path)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True, env=env)
    runs = copies(path, a, a.batch)
    clock = {}
    gpu = report("gpu", runs, a, *timed(runs, lambda rs, job: run_batched(
        rs, job, check_every=a.check_every, clock=clock), "gpu", a.cycles, a.budget, clock))
    if a.kernels:
        breakdown(runs, a)
    try:                    # the CPU's cycle 0 can outlast the GPU's cycles by far
        out, _ = child.communicate(timeout=None if a.budget == float("inf") else a.budget)
    except subprocess.TimeoutExpired:
        child.kill()
        out = child.communicate()[0] + "\n[cpu] stopped: --budget spent after the GPU part"
    print("\n".join(line for line in out.splitlines() if not line.startswith("CPU_RESULT")))
    cpu = next((json.loads(line.split(" ", 1)[1])["minutes"] for line in out.splitlines()
                if line.startswith("CPU_RESULT")), float("nan"))
    what = (f"{a.width:g} x {a.height:g} m, {a.frequency:g} Hz" if a.rig == "biaxial"
            else a.config)
    print(f"gpu_batch_minutes_per_1000_cycles={gpu:.2f} ({a.rig}, B={a.batch}, {what})")
    print(f"cpu_one_case_minutes_per_1000_cycles={cpu:.2f} (one thread); the batch does "
          f"{a.batch * cpu / gpu:.1f} x the CPU's case-cycles per hour")
    return 0


if __name__ == "__main__":
    sys.exit(main())
