"""Box-test case benchmark over several packings (seeds), beside a reference checkout.

    NUMBA_NUM_THREADS=1 python bench/case_seeds.py --seeds 1 2 3 4 [--reference SRC]
        [--settle2d] [any other bench/case_benchmark.py option, e.g. --cycles 100
        --library BPM.nc --config config/thesis.yaml]

Minutes per 1000 cycles = steps per cycle x time per step, and the steps per cycle vary
with the packing (3550-5250 at the thesis resolution, seeds 1-4) by more than an engine
change moves the time per step: one seed cannot tell whether the 3-minute goal is met.
This runs bench/case_benchmark.py once per seed (with --reference, SRC's own copy first in
the same run, as case_benchmark does), prints each run's numbers per seed and then the
means over the seeds; the last line is ``minutes_per_1000_cycles_mean=<x>``. Never a test.
"""
import argparse
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
KEYS = {"time_per_step_us": r"time_per_step_us=([\d.]+)",
        "steps_per_cycle": r"steps_per_cycle=([\d.]+)",
        "minutes_per_1000_cycles": r"minutes_per_1000_cycles=([\d.]+)",
        "case_over_settle2d": r"case / settle2d = ([\d.]+)"}


def numbers(lines):
    """The benchmark's numbers from its output lines (absent ones: nan)."""
    text = "\n".join(lines)
    return {k: float(m.group(1)) if (m := re.search(p, text)) else float("nan")
            for k, p in KEYS.items()}


def one_seed(seed, rest):
    """(ours, reference or None) numbers of one case_benchmark run at ``seed``."""
    out = subprocess.run([sys.executable, str(HERE / "case_benchmark.py"), "--seed", str(seed)]
                         + rest, text=True, capture_output=True, cwd=HERE.parent)
    if out.returncode != 0:
        sys.exit(f"case_benchmark failed at seed {seed}:\n{out.stdout}{out.stderr}")
    lines = out.stdout.splitlines()
    ref = [ln.split(": ", 1)[1] for ln in lines if ln.startswith("reference ") and ": " in ln]
    ours = [ln for ln in lines if not ln.startswith("reference ")]
    return numbers(ours), (numbers(ref) if ref else None)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    a, rest = ap.parse_known_args(argv)
    rows = []
    for s in a.seeds:
        ours, ref = one_seed(s, rest)
        rows.append((ours, ref))
        for name, r in (("reference", ref), ("ours", ours)):
            if r is not None:
                print(f"seed {s} {name}: " + " ".join(f"{k}={v:.3g}" for k, v in r.items()),
                      flush=True)
    for name, pick in (("reference", 1), ("ours", 0)):
        got = [r[pick] for r in rows if r[pick] is not None]
        if got:
            print(f"mean over seeds {a.seeds} {name}: " + " ".join(
                f"{k}={np.mean([g[k] for g in got]):.3g}" for k in KEYS))
    print(f"minutes_per_1000_cycles_mean={np.mean([r[0]['minutes_per_1000_cycles'] for r in rows]):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
