"""A long loading run's behaviours against log N, from its metrics.nc or, while it runs or
after it was stopped, from its checkpoint (the per-cycle rows it holds).

    python bench/long_run.py RUN/metrics.nc [--at 1 10 100 1000 10000 100000]

Prints per N the settlement [mm], the breakage rate [%], the broken mass share [%] (NaN in
files written before it existed), the void ratio and the force propagation angle at the
end of cycle N (1-based), and the settlement gained per decade of N. Never a test."""
import argparse
from pathlib import Path

import numpy as np
import xarray as xr

from ballaststudy.rig.cyclic import json_of

NAMES = (("settlement", 1e3, "mm"), ("breakage_rate", 100.0, "%"), ("broken_mass_share", 100.0, "%"),
         ("void_ratio", 1.0, "1"), ("fpa", 1.0, "deg"))


def rows(path):
    """{name: (N,) array} of the run's per-cycle behaviours and where they came from."""
    path = Path(path)
    if path.is_file():
        with xr.open_dataset(path) as ds:
            return {n: ds[n].values.astype(float) if n in ds else np.full(ds.sizes["cycle"], np.nan)
                    for n, _, _ in NAMES}, str(path)
    ckpt = path.with_name(path.stem + ".checkpoint.npz")
    with np.load(ckpt) as z:
        state = json_of(z["state"])
    return ({n: np.array([r.get(n, np.nan) for r in state["rows"]], float) for n, _, _ in NAMES},
            f"{ckpt} (cycle {state['cycle']})")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("metrics")
    ap.add_argument("--at", type=int, nargs="+", default=[1, 10, 100, 1000, 10000, 100000])
    a = ap.parse_args(argv)
    data, source = rows(a.metrics)
    n = len(data["settlement"])
    print(f"{source}: {n} cycles")
    print("       N " + " ".join(f"{name} [{u}]".rjust(22) for name, _, u in NAMES))
    prev = None
    for at in [k for k in a.at if k <= n]:
        vals = [data[name][at - 1] * s for name, s, _ in NAMES]
        gain = "" if prev is None else f"   +{vals[0] - prev:.3f} mm since the N before"
        print(f"{at:8d} " + " ".join(f"{v:22.4f}" for v in vals) + gain)
        prev = vals[0]


if __name__ == "__main__":
    main()
