"""Batched GPU engine: aggregate throughput of B settle2d cases stepped together.

    python bench/gpu_ensemble.py [--n 5000] [--steps 2000] [--batches 1,10,100,1000]
        [--forces-registers 128,96,64]
        [--cpu-steps 2000] [--check-steps 500]

Needs a CUDA GPU and numba-cuda (``pip install -e '.[cuda]'``); prints one line and exits
2 without one. Prints, in this order:

1. ``gpu=...``: the device and the numba / numba-cuda versions.
2. Agreement with the CPU engine: three settle2d beds (300, 400, 500 disks) and a bonded
   one (400 disks in flat-jointed clusters, bench/engine_vs_lammps.py's variant) first
   settled on the CPU, then advanced ``--check-steps`` steps on both engines from the same state;
   the largest position and velocity differences (round-off grows in a granular bed, so
   this is a check of the same physics, not of equal bits).
3. The CPU engine's figure for one case (``--n`` disks, ``--cpu-steps`` steps from the
   lattice, one thread, bench/engine_vs_lammps.py's run), measured in a subprocess that
   runs beside the GPU part (its JIT compile takes a minute on a cold cache).
4. For each B: B copies of the settle2d case of ``--n`` disks (../shared/bench/README.md)
   stepped ``--steps`` steps from the lattice in one batch; wall-clock over the steps after
   a first step (first neighbour build), the device synchronised before reading the clock
   (``--bonded-batches``: the same for the bonded variant);
   ball-steps/s = B n steps / s. The copies are identical cases: the work per step is that
   of B independent cases, which is what the throughput counts.
   For B = 1, 100 and 1000, 100 more steps with each kernel timed alone (device
   synchronised before and after it): where the step's time goes.
5. With --forces-registers: B = 100 and 1000 (and bonded 100) again with the forces
   kernel's registers capped at each value (occupancy against spills).
6. Where the rigs' figures come from: bench/gpu_rigs.py (the rigs' cycles on the batch).

The last line is a table. A script that prints numbers, never a test.
"""
import argparse
import copy
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from engine_vs_lammps import build  # noqa: E402

CPU_CHILD = """
import json, sys
sys.path.insert(0, {here!r})
import engine_vs_lammps as e
e.warm_up()
r = e.run_ours({n}, {steps})
print("CPU_RESULT " + json.dumps(dict(bsps=r["bsps"], loop_s=r["loop_s"])))
"""


def start_cpu_reference(n, steps):
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    return subprocess.Popen([sys.executable, "-c", CPU_CHILD.format(here=HERE, n=n, steps=steps)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)


def cpu_reference(proc):
    out, _ = proc.communicate()
    for line in out.splitlines():
        if line.startswith("CPU_RESULT "):
            return json.loads(line.split(" ", 1)[1])
    print("# CPU reference failed:\n" + out[-3000:], flush=True)
    return None


def agreement(steps):
    from ballaststudy.dem.gpu import Batch
    beds = []
    for n, bonded in ((300, False), (400, False), (500, False), (400, True)):
        s = build(n, bonded)
        s.run(6000)                      # settled on the CPU: a bed full of contacts
        beds.append(s)
    cpu = [copy.deepcopy(s) for s in beds]
    gpu = [copy.deepcopy(s) for s in beds]
    for s in cpu:
        s.run(steps)
    batch = Batch.from_simulations(gpu)
    batch.run(steps)
    batch.to_simulations(gpu)
    print("prepared launches: " + ", ".join(k for k, v in batch.prepared.items() if v)
          + "; ordinary: " + ", ".join(k for k, v in batch.prepared.items() if not v),
          flush=True)
    for c, g in zip(cpu, gpu):
        r = float(c.balls.rad.mean())
        dp = float(np.abs(c.balls.pos - g.balls.pos).max())
        dv = float(np.abs(c.balls.vel - g.balls.vel).max())
        vmax = float(np.abs(c.balls.vel).max())
        bonds = ""
        if len(c.bonds):
            dfn = float(np.abs(c.bonds.fn - g.bonds.fn).max())
            bonds = (f", {len(c.bonds)} flat joints: max|dF_n| {dfn:.3g} N (max {np.abs(c.bonds.fn).max():.3g}), "
                     f"breakages {len(c.breakages()['step'])} / {len(g.breakages()['step'])}")
        print(f"agreement n={len(c.balls)} steps={steps}: max|dpos|={dp:.3g} m "
              f"({dp / r:.2g} R_mean), max|dvel|={dv:.3g} m/s (max|v| {vmax:.3g}), "
              f"touching contacts {int((c.pairs.fn[:c.pairs.n[0]] != 0).sum())}{bonds}",
              flush=True)


def gpu_throughput(n, steps, batches, phases=(1, 100, 1000), bonded=False, registers=None):
    from ballaststudy.dem.gpu import Batch
    from numba import cuda
    rows = []
    tag = (" bonded" if bonded else "") + (f" cap {registers}" if registers else "")
    for nb in batches:
        sim = build(n, bonded)
        try:
            batch = Batch.from_simulations([sim] * nb, forces_registers=registers)
            batch.run(1)
            cuda.synchronize()
            t0 = time.perf_counter()
            batch.run(steps, check_every=steps)
            cuda.synchronize()
            t = time.perf_counter() - t0
        except Exception as exc:       # out of memory, a failed case: say so, go on
            print(f"B={nb}: failed: {exc}", flush=True)
            rows.append((f"{nb}{tag}", n, steps, float("nan"), float("nan")))
            continue
        bsps = nb * n * steps / t
        pos = batch.case_arrays(0, "pos")[0]
        print(f"B={nb}{tag}: {nb * n} balls, {steps} steps in {t:.3f} s: {bsps:.3g} ball-steps/s "
              f"({1e6 * t / steps:.1f} us/step); case 0 mean y {pos[:, 1].mean():.4f} m",
              flush=True)
        rows.append((f"{nb}{tag}", n, steps, t, bsps))
        if nb in phases:           # each kernel timed alone (device synchronised around it)
            batch.timer = {}
            batch.run(100, check_every=100)
            print(f"B={nb} phases (us/step, each launch synchronised): " + ", ".join(
                f"{k} {1e4 * v:.0f}" for k, v in batch.timer.items()), flush=True)
        del batch
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--batches", default="1,10,100,1000")
    ap.add_argument("--bonded-batches", default="100",
                    help="B of the bonded variant (bench/engine_vs_lammps.py's clusters)")
    ap.add_argument("--forces-registers", default="",
                    help="caps on a forces thread's registers to time too, e.g. 128,96,64 "
                    "(B = 100 and 1000, and bonded 100, each)")
    ap.add_argument("--cpu-steps", type=int, default=2000)
    ap.add_argument("--check-steps", type=int, default=500)
    a = ap.parse_args()
    from ballaststudy.dem.gpu import cuda_available
    if not cuda_available():
        print("gpu_ensemble.py: no CUDA GPU visible to numba (install '.[cuda]' on a machine "
              "with a GPU)", file=sys.stderr)
        sys.exit(2)
    import numba
    from numba import cuda
    try:
        from importlib.metadata import version
        nc = version("numba-cuda")
    except Exception:
        nc = "built-in"
    if numba.config.ENABLE_CUDASIM:
        name, cc = "CUDA simulator (not a GPU: a dry run of this script)", "-"
    else:
        dev = cuda.get_current_device()
        name = dev.name.decode() if isinstance(dev.name, bytes) else dev.name
        cc = dev.compute_capability
    print(f"gpu={name} cc={cc} numba={numba.__version__} numba-cuda={nc}", flush=True)
    proc = start_cpu_reference(a.n, a.cpu_steps)
    t0 = time.perf_counter()
    agreement(a.check_steps)
    print(f"# agreement (incl. CUDA compile): {time.perf_counter() - t0:.1f} s", flush=True)
    rows = gpu_throughput(a.n, a.steps, [int(b) for b in a.batches.split(",")])
    rows += gpu_throughput(a.n, a.steps, [int(b) for b in a.bonded_batches.split(",") if b],
                           phases=(), bonded=True)
    for cap in (int(r) for r in a.forces_registers.split(",") if r):
        rows += gpu_throughput(a.n, a.steps, [100, 1000], phases=(), registers=cap)
        rows += gpu_throughput(a.n, a.steps, [100], phases=(), bonded=True, registers=cap)
    cpu = cpu_reference(proc)
    cpu_bsps = cpu["bsps"] if cpu else float("nan")
    print(f"cpu_engine_one_case_ball_steps_per_s={cpu_bsps:.3g} (n={a.n}, {a.cpu_steps} steps, "
          f"one thread)")
    print("rigs on the batch: bench/gpu_rigs.py (100 full-size biaxial specimens' real-time "
          "cycles; --rig box --batch 160 --config config/thesis.yaml: the study's box cases)")
    print("| B | balls | steps | s | ball-steps/s | x CPU one case |")
    print("|---|---|---|---|---|---|")
    for nb, n, steps, t, bsps in rows:
        print(f"| {nb} | {int(nb.split()[0]) * n} | {steps} | {t:.3f} | {bsps:.3g} | {bsps / cpu_bsps:.1f} |")


if __name__ == "__main__":
    main()
