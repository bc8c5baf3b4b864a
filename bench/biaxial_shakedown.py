"""Shake-down of unbreakable stones over many biaxial specimens: how often the property of
tests/rig/test_biaxial.py::test_unbreakable_stones_shake_down holds.

    NUMBA_NUM_THREADS=1 [PYTHONPATH=/path/to/checkout/src] python bench/biaxial_shakedown.py
        --seeds 7 8 9 10 11 [--perturb 1e-12]

Per seed: the test's small specimen (24 synthetic stones, its parameters) assembled with
the package on the path, bond strengths x 1e6, 50 cycles of q; then the permanent axial
strain of cycles 1-10 ("early") and 40-49 ("late") and whether early > 0 and early >= 5
|late| (the test's assertion). ``--perturb SD`` adds a normal draw of SD [m/s] to the free
balls' velocities at the assembly's first run (the stones placed, before the drop): a
round-off-sized change of the whole trajectory, the control for an engine change that
differs from its reference by round-off only. (Perturbed later, at the second run, the
runs keep the reference's landing, which decides most of the outcome.) The test asserts this on one specimen (seed 7), so
what matters for a change is the pass rate over seeds beside its reference's (with and
without the perturbation). Never a test.
"""
import argparse
import os
import tempfile
import weakref
from pathlib import Path

import numpy as np

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

SMALL = dict(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
             fill_area_ratio=0.9, consolidation_window_steps=1000, checkpoint_every=1,
             deviator_min_kPa=10.0, deviator_max_kPa=60.0)


def perturb_each_assembly(sd):
    """Simulation.run wrapped: the first call on each Simulation (an assembly's first run,
    its stones placed) perturbs the velocities first."""
    from ballaststudy.dem.simulation import Simulation
    plain = Simulation.run
    seen = weakref.WeakSet()

    def run(self, *args, **kwargs):
        if self not in seen:
            seen.add(self)
            self.perturb_velocities(sd, seed=1)
        return plain(self, *args, **kwargs)
    Simulation.run = run


def shakedown(library, seed):
    """(early, late) permanent axial strain sums of one specimen."""
    from ballaststudy.rig.biaxial import BiaxialParams, BiaxialRun, assemble_biaxial
    from ballaststudy.rig.library import load_library
    rig = assemble_biaxial(load_library(library), BiaxialParams(**SMALL), seed=seed)
    rig.sim.scale_bond_strength(1e6)
    run = BiaxialRun(rig, cycles=50).run()
    ea = np.array([r["axial_strain"] for r in run.s.rows])
    return ea[10] - ea[0], ea[49] - ea[39]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[7, 8, 9, 10, 11])
    ap.add_argument("--perturb", type=float, default=0.0, help="velocity draw sd [m/s]")
    a = ap.parse_args(argv)
    from ballaststudy.rig.library import synthetic_library
    library = Path(tempfile.mkdtemp()) / "BPM.nc"
    synthetic_library(24, size=(0.035, 0.065), r0=0.008, seed=3, database="tiny").to_netcdf(library)
    if a.perturb > 0.0:
        perturb_each_assembly(a.perturb)
    passed = 0
    for seed in a.seeds:
        early, late = shakedown(library, seed)
        ok = early > 0 and 5 * abs(late) <= early
        passed += ok
        print(f"seed {seed}: early {early:.3e} late {late:.3e} "
              f"ratio {early / abs(late) if late else float('inf'):.3g} shakes_down={ok}", flush=True)
    print(f"shakes_down {passed} of {len(a.seeds)} (perturb {a.perturb:g} m/s)")


if __name__ == "__main__":
    main()
