"""How confined a stone is where it splits: (sigma_1 - sigma_3) / sigma_c of rigid stones
between two platens (the crushing test) and in the box bed at the first cycle's peak.

    NUMBA_NUM_THREADS=1 python bench/criterion_confinement.py results/bpm/box_test.nc \
        results/cases/box_test/case1/assembled.nc [--stones 10]

sigma_c = F_max / (d t) is the splitting criterion of dem/crushing.py (the largest force
from one neighbour); sigma_1 - sigma_3 is the deviator of the stone's average stress
(1/(A t)) sum f (x) r, which the same kernel sums. Between two platens a stone has no other
contact; in the bed its other contacts confine it, and the ratio says by how much a
criterion on the deviator, calibrated on the platens, would raise the stones' strength in
the bed. Never a test."""
import argparse
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from ballaststudy.dem import crushing  # noqa: E402
from ballaststudy.rig.box import BoxRig  # noqa: E402
from ballaststudy.rig.crushing import CrushingParams, _platen_sim  # noqa: E402
from ballaststudy.rig.library import load_library  # noqa: E402
from ballaststudy.rig.loading import LoadingRun  # noqa: E402
from ballaststudy.stones import stone_model  # noqa: E402


def ratios(sim):
    """(sigma_c, (sigma_1 - sigma_3) / sigma_c) per clump now."""
    t = sim.thickness
    fmax, s, area = crushing.loads(sim)
    sig_c, dev = (crushing.characteristic_stress(t, fmax, s, area, k) for k in (0, 1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return sig_c, dev / sig_c


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("library")
    ap.add_argument("box_case")
    ap.add_argument("--stones", type=int, default=10)
    ap.add_argument("--steps", type=int, default=3000, help="platens closed this long (0.01 m/s each)")
    a = ap.parse_args(argv)
    lib, p = load_library(a.library), CrushingParams()
    platen = []
    for k in range(a.stones):
        sim, ids, _, _, _ = _platen_sim(lib, k, 0.3 * k, p)
        stone_model("rigid").make(sim, ids, None)
        sim.run(a.steps)
        platen.append(ratios(sim)[1][0])
    print(f"platens, {a.stones} stones: (sigma_1 - sigma_3) / sigma_c {np.round(platen, 2)}, "
          f"median {np.nanmedian(platen):.2f}")
    rig = BoxRig.load(a.box_case)
    rig.use_stone_model("rigid")
    run, peaks = LoadingRun(rig, cycles=1), []
    run.on_peak = lambda: peaks.append(ratios(rig.sim))
    run.run()
    sig_c, r = peaks[0]
    loaded = np.flatnonzero((rig.sim.clumps.held == 0) & (sig_c > 0))
    top = loaded[np.argsort(sig_c[loaded])[::-1][:15]]
    print(f"bed at cycle 0's peak, the 15 most loaded stones: sigma_c [MPa] {np.round(sig_c[top] / 1e6, 3)}")
    print(f"  (sigma_1 - sigma_3) / sigma_c {np.round(r[top], 2)}, median {np.nanmedian(r[top]):.2f}; "
          f"all {len(loaded)} loaded stones: median {np.nanmedian(r[loaded]):.2f}")


if __name__ == "__main__":
    main()
