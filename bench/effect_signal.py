"""The candidate effects' signal at a measured test's stress level, against the scatter
between specimens (issue 34: can the loop see an effect where the measured tests load?).

    python bench/effect_signal.py S0.nc S1.nc ... --test config/measured/sun_et_al_16/p60_q230_f20.yaml
        [--config config/config.yaml] [--cycles 12] [--points 1 5 10] [--jobs 2]
        [--effects rate abrasion end_restraint] [--stiffer 2.0] [--out DIR]

S0... : assembled biaxial specimens the loop never saw (e.g. `ballaststudy case assemble
results/bpm/box_test.nc --case 10 --rig biaxial --width-m 0.15 --height-m 0.30`). Every
specimen runs under the test's conditions (read through the importer; stress mapping none)
as the loop runs them (calibration.evaluate.Evaluator, the loop's runner): the plain model
(Table 4.2), each effect at the middle of its parameter's range, and one change outside
the library, the stone contact's E* times --stiffer. Prints per model and specimen the
axial strain at the points (or where it gave way), then per model and point:

  signal   the mean over specimens of (model - plain) on the same specimen (common random
           numbers: the effect alone), over the specimens where both carried the load;
  scatter  the sd over specimens of the plain model's strain: how far a laboratory
           specimen (never one of ours) lies from our ensemble's mean, before any effect;
  ratio    |signal| / scatter.

A planted truth on a fresh specimen deviates from the plain ensemble by signal + a
specimen's offset; the loop's rule keeps an effect only if its held-out cut exceeds what
that scatter leaves (loop/select.py), whatever K is. A ratio well below 1 means no number
of our specimens lets the loop name the effect from tests on other specimens at this
scale; K only sharpens our ensemble's mean. Never a test.

Measured 2026-11-29 (commit 2bb5978; 50 min on 2 cores): Sun et al.'s p60_q230_f20, six
fresh 0.15 x 0.30 m box_test specimens (cases 10-15 of the default seed), 12 cycles:
  - plain: none gave way (the loop's two specimens: one of two did); axial strain at N = 10
    0.39-3.43 %, sd 1.04 % between specimens (0.62-1.24 % at N = 1-10 over the subsets);
  - rate (damping ratio 0.375, real time, no local damping): 5 of 6 gave way: its signal
    at this load is failure, which the laboratory specimen did not show;
  - abrasion (wear 0.1 a cycle): +0.04 % at N = 10, ratio 0.04; none gave way;
  - end restraint (platen friction 0.6): +0.58 % at N = 10 (two specimens of five), ratio
    0.51; one gave way;
  - E* x 2 (out of library): -0.03 %, ratio 0.04; one gave way.
No effect stands beyond the scatter between specimens at this scale (the rule asks the
squared cut to exceed it: ratio > 1), whatever K: the loop cannot name >= 3 of 4 effects
here, and the out-of-library control cannot be told from none. The scatter is the first
loading's (strain at N = 1 already spreads 0.35-3.3 %); the effects act over cycles, so a
horizon of 1000 cycles, where they accumulate, is where they can outgrow it."""
import argparse
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from ballaststudy.calibration.evaluate import Evaluator  # noqa: E402
from ballaststudy.config import load_config  # noqa: E402
from ballaststudy.dem.materials import ContactMaterial  # noqa: E402
from ballaststudy.scenario.modifiers import MODIFIERS  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("specimens", nargs="+", type=Path)
    ap.add_argument("--test", type=Path, required=True, help="a measured test's conditions YAML")
    ap.add_argument("--config", type=Path, default=Path("config/config.yaml"))
    ap.add_argument("--cycles", type=int, default=12)
    ap.add_argument("--points", type=float, nargs="+", default=[1.0, 5.0, 10.0])
    ap.add_argument("--effects", nargs="+", default=["rate", "abrasion", "end_restraint"])
    ap.add_argument("--stiffer", type=float, default=2.0, help="the out-of-library E* factor (0: none)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", type=Path, help="case cache (default: a temporary folder)")
    a = ap.parse_args(argv)

    cfg = load_config(a.config)
    out = a.out or Path(tempfile.mkdtemp(prefix="effect_signal_"))
    points = np.asarray(a.points, float)

    def evaluate(names, values, effect=None, base=None):
        # the plain cases keep their cycle-0 state for a hook-only effect (abrasion), as in the loop
        share = effect is None and base is None or effect is not None and MODIFIERS[effect].hook_only
        ev = Evaluator(names, a.specimens, [(a.test, points)], cfg, a.cycles, "axial_strain", out,
                       jobs=a.jobs, effect=effect, base=base, share_first_loading=share)
        at = ev(np.array([values], float))[0]                                   # (K, P)
        return at, np.array(ev.sets[-1]["failed"][0], bool)

    models = {"plain": evaluate([], [])}                  # first: abrasion goes on from its cycle 0
    for name in a.effects:
        p = MODIFIERS[name].parameters[0]
        models[f"{name} {p.name}={0.5 * (p.low + p.high):g}"] = evaluate(
            [p.name], [0.5 * (p.low + p.high)], effect=name)
    if a.stiffer:
        models[f"E* x {a.stiffer:g} (out of library)"] = evaluate(
            [], [], base={"E_star": a.stiffer * ContactMaterial().E})

    print(f"{a.test.name}: {len(a.specimens)} specimens, {a.cycles} cycles, points N = "
          f"{', '.join(f'{n:g}' for n in points)}; cases in {out}")
    print("\naxial strain [%] per specimen at the last point (F: gave way)")
    for name, (at, failed) in models.items():
        print(f"  {name:36s} " + " ".join("   F   " if f else f"{100 * v:7.3f}" for v, f in zip(at[:, -1], failed)))
    plain, plain_failed = models["plain"]
    print("\nper model and point: signal (mean paired difference from plain) and scatter (sd of "
          "plain over specimens) [% strain], their ratio; specimens where both carried the load")
    for name, (at, failed) in list(models.items())[1:]:
        both = ~(failed | plain_failed)
        print(f"  {name}: {both.sum()} of {len(both)} specimens carried the load under both "
              f"(gave way: {failed.sum()} here, {plain_failed.sum()} plain)")
        for j, n in enumerate(points):
            if both.sum() < 2:
                print(f"    N = {n:g}: too few specimens")
                continue
            signal = float(np.mean(at[both, j] - plain[both, j]))
            scatter = float(np.std(plain[both, j], ddof=1))
            print(f"    N = {n:5g}: signal {100 * signal:+8.4f}, scatter {100 * scatter:7.4f}, "
                  f"ratio {abs(signal) / scatter if scatter > 0 else np.inf:6.2f}")


if __name__ == "__main__":
    sys.exit(main())
