"""Box-test cases before and after a change, side by side (refactors must keep the physics).

    python bench/box_before_after.py run --src /path/to/old/checkout --out /tmp/before \
        [--seeds 1 2 3] [--cycles 20] [--library BPM.nc] [--config config/config.yaml]
    python bench/box_before_after.py run --src . --out /tmp/after ...
    python bench/box_before_after.py compare /tmp/before /tmp/after

``run`` assembles and loads one box_test case per seed with the package found under
``--src/src`` (a clean checkout of the revision to measure; its own numba cache), through
the CLI in a subprocess, and keeps ``a<seed>.nc`` / ``m<seed>.nc``. The library defaults to
box_test at the thesis resolution (config/thesis.yaml's bpm section), built once and cached
in results/bench_cache. ``compare`` prints per seed the settlement, flat-joint elements
broken, breakage rate and void ratio after the last cycle, then the mean difference after -
before next to the case-to-case standard deviation of the "before" cases: a change that
keeps the physics shows differences within that scatter (trajectories are chaotic, so equal
numbers are not expected unless the arithmetic is unchanged). Never a test.
"""
import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
CACHE = HERE.parent / "results" / "bench_cache"


def _cli(src, args):
    env = dict(os.environ, PYTHONPATH=str(Path(src).resolve() / "src"), NUMBA_NUM_THREADS="1")
    code = f"from ballaststudy.cli import main; main({args!r})"
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=HERE.parent)


def thesis_library(src):
    """box_test forms + BPM library at the thesis resolution (built once)."""
    bpm = CACHE / "box_test_thesis_bpm.nc"
    if not bpm.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        forms = CACHE / "box_test.nc"
        if not forms.exists():
            _cli(src, ["forms", "generate", "box_test", "--out", str(CACHE), "--config",
                       "config/thesis.yaml", "--quiet"])
        _cli(src, ["bpm", "build", str(forms), "--out", str(bpm), "--config",
                   "config/thesis.yaml", "--quiet"])
    return bpm


def run(a):
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    lib = a.library or str(thesis_library(a.src))
    for s in a.seeds:
        _cli(a.src, ["case", "assemble", lib, "--case", str(s), "--seed", str(s), "--out",
                     str(out / f"a{s}.nc"), "--config", a.config, "--quiet"])
        _cli(a.src, ["case", "run", str(out / f"a{s}.nc"), "--cycles", str(a.cycles), "--out",
                     str(out / f"m{s}.nc"), "--config", a.config, "--quiet", "--no-vtk",
                     "--no-figures", "--restart"])
        print(f"seed {s}: {out / f'm{s}.nc'}", flush=True)


def final_values(path):
    import xarray as xr
    with xr.open_dataset(path) as ds:
        return dict(settlement_mm=1e3 * float(ds.settlement[-1]),
                    broken=int(ds.broken_tension[-1] + ds.broken_shear[-1]),
                    breakage_rate_pct=100 * float(ds.breakage_rate[-1]),
                    void_ratio=float(ds.void_ratio[-1]), cycles=int(ds.sizes["cycle"]))


def compare(a):
    import numpy as np
    before, after = Path(a.before), Path(a.after)
    seeds = sorted(int(p.stem[1:]) for p in before.glob("m*.nc") if (after / p.name).exists())
    if not seeds:
        print("no seed has a metrics file in both folders", file=sys.stderr)
        return 2
    keys = ("settlement_mm", "broken", "breakage_rate_pct", "void_ratio")
    rows = {s: (final_values(before / f"m{s}.nc"), final_values(after / f"m{s}.nc")) for s in seeds}
    print(f"after cycle {rows[seeds[0]][0]['cycles'] - 1}, before / after:")
    print("seed  " + "  ".join(f"{k:>22s}" for k in keys))
    for s, (b, f) in rows.items():
        print(f"{s:4d}  " + "  ".join(f"{b[k]:10.4g} / {f[k]:<9.4g}" for k in keys))
    for k in keys:
        b = np.array([rows[s][0][k] for s in seeds], float)
        f = np.array([rows[s][1][k] for s in seeds], float)
        d = f - b
        sd = b.std(ddof=1) if len(b) > 1 else float("nan")
        print(f"{k}: mean before {b.mean():.4g}, after {f.mean():.4g}; mean difference "
              f"{d.mean():+.4g} (standard error {d.std(ddof=1) / np.sqrt(len(d)):.2g}) vs "
              f"case-to-case sd {sd:.4g}")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--src", required=True, help="checkout whose src/ballaststudy is measured")
    r.add_argument("--out", required=True)
    r.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    r.add_argument("--cycles", type=int, default=20)
    r.add_argument("--library", help="BPM library (default: box_test, thesis resolution)")
    r.add_argument("--config", default="config/config.yaml")
    c = sub.add_parser("compare")
    c.add_argument("before")
    c.add_argument("after")
    a = ap.parse_args(argv)
    return run(a) if a.cmd == "run" else compare(a)


if __name__ == "__main__":
    sys.exit(main())
