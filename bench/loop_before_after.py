"""The loop before and after a change, on a tiny loop: the inputs of tests/loop/test_cli.py
(3 planted tests at q 10-50 kPa, t0 and t1 differ in f only; 2 specimens of 0.12 x 0.24 m;
5 cycles; candidates ``--effects``) made once in OUT, then `ballaststudy loop` run by each
source tree given (its src/ on PYTHONPATH), one after the other in this invocation; prints
each one's wall time and case files, and whether every loop.nc variable and attribute and
report.md are the same.

    python bench/loop_before_after.py OUT /path/to/old/checkout/src src --effects rate abrasion
"""
import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import xarray as xr
import yaml

root = Path(__file__).resolve().parents[1]
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("out", type=Path)
ap.add_argument("srcs", nargs=2, help="the two source trees (their src/ folders)")
ap.add_argument("--effects", nargs="+", default=["rate", "abrasion"])
args = ap.parse_args()
out, srcs = args.out, [str(Path(s).resolve()) for s in args.srcs]
out.mkdir(parents=True, exist_ok=True)
sys.path.insert(0, str(root / "src"))
from ballaststudy.cli import main  # noqa: E402
from ballaststudy.rig.library import synthetic_library  # noqa: E402
from ballaststudy.measured.importer import import_test  # noqa: E402
FAST = dict(consolidation_window_steps=1000, first_loading_inertial_number=1.35e-4)
lib = out / "BPM.nc"
if not lib.exists():
    synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(lib)
cfg = yaml.safe_load((root / "config" / "config.yaml").read_text())
cfg["databases_file"] = str(root / cfg["databases_file"])
cfg["rig"]["biaxial"]["loading"].update(FAST)
cfg["loop"].update(dict(cases=2, cycles=5, design_sets=2, refine_rounds=1, refine_sets=2,
                        effects=args.effects, measurement_sd=1e-4, posterior_samples=256))
config = out / "config.yaml"
config.write_text(yaml.safe_dump(cfg))
specimens = [out / f"s{k}.nc" for k in range(2)]
for k, s in enumerate(specimens):
    if not s.exists():
        assert main(["case", "assemble", str(lib), "--case", str(k), "--rig", "biaxial", "--width-m", "0.12",
                     "--height-m", "0.24", "--config", str(config), "--out", str(s), "--quiet"]) == 0
measured, conditions = [], []
for j, (p, f) in enumerate([(30, 5), (30, 40), (40, 20)]):
    c = out / f"t{j}.yaml"
    c.write_text(yaml.safe_dump(dict(source="planted", rig="triaxial", confining_pressure_kPa=p,
        deviator_min_kPa=10.0, deviator_max_kPa=50.0, frequency_Hz=f, curves=[dict(file=f"t{j}.dat",
        quantity="axial_strain", units="1", sign="compression_positive")])))
    n = np.array([1.0, 1.7, 2.5, 3.9, 4.6, 30.0, 500.0])
    (out / f"t{j}.dat").write_text("".join(f"{a}, {0.001 + 0.0005 * np.log(a)}\n" for a in n))
    conditions.append(c); measured.append(out / f"t{j}.nc")
    if not measured[-1].exists():
        import_test(c, measured[-1])
results = []
for i, src in enumerate(srcs):
    d = out / f"loop{i}"
    t0 = time.time()
    env = {**os.environ, "PYTHONPATH": src}
    subprocess.run([sys.executable, "-c", "import sys; from ballaststudy.cli import main; sys.exit(main(sys.argv[1:]))",
                    "loop", *map(str, measured), "--conditions", *map(str, conditions), "--specimens",
                    *map(str, specimens), "--out-dir", str(d), "--config", str(config), "--quiet", "--jobs", "2"],
                   check=True, env=env)
    n = len(list((d / "cases").rglob("*.nc")))
    print(f"{src}: {time.time() - t0:.1f} s wall, {n} case files")
    results.append(xr.load_dataset(d / "loop.nc"))
a, b = results
same = {k: np.array_equal(a[k].values, b[k].values, equal_nan=a[k].dtype.kind == "f") for k in a.data_vars}
print("variables:", len(same), "bitwise equal:", sum(same.values()), "differ:", [k for k, v in same.items() if not v])
attrs = [k for k in a.attrs if a.attrs[k] != b.attrs.get(k)]
print("attributes that differ:", attrs)
reports = [(out / f"loop{i}" / "report.md").read_text().splitlines() for i in range(2)]
print("report.md lines that differ:", [(x, y) for x, y in zip(*reports) if x != y])
