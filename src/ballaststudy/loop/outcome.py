"""What one `ballaststudy loop` run produced, bundled for its outputs (loop/report.py).

The statistics, loop.nc, chosen.yaml, report.md and curves.png each take one LoopRun
instead of a dozen positional arguments, and never the command line: the bundle names what
the outputs read, so a reader sees it in one place and a test can build one by hand."""
from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Targets:
    """The measured tests the loop ran against (loop.targets), in the loop's order."""
    conditions: list     # paths of their conditions YAML (measured.importer.load_conditions)
    measured: list       # paths of their measured netCDF: every point, beyond the DEM horizon too
    points: list         # (N, values) per test within the simulated cycles (the DEM horizon)

    @property
    def names(self):
        return [Path(c).with_suffix("").name for c in self.conditions]

    @property
    def y(self):
        """(P,) the tests' points one after the other: the order of every per-point array."""
        return np.concatenate([v for _, v in self.points])

    @property
    def point_cycle(self):
        """(P,) load cycle N of each point."""
        return np.concatenate([n for n, _ in self.points])

    @property
    def point_test(self):
        """(P,) the test of each point."""
        return np.concatenate([np.full(n.size, j) for j, (n, _) in enumerate(self.points)])


@dataclass(frozen=True)
class PlainModel:
    """The model without an effect: its runs and how it was judged."""
    runs: dict                 # its Evaluator set: "curves" (T, K, cycles), "cases" (files)
    prediction: np.ndarray     # (P,) its ensemble mean at the measured points
    held: object               # select.HeldOut (nothing fitted, so held out = fitted)
    probe: dict = None         # the chaos probe's set (specimen_share 0), else None


@dataclass(frozen=True)
class Selection:
    """The candidate effects, judged, and what the rule chose."""
    candidates: dict           # {effect: loop.cli.Candidate}
    evidence: dict             # {effect: select.choose's gain, se, z, wins, tests, p}
    chosen: str = None         # None: no effect chosen, the model stays plain
    after: dict = None         # the chosen effect's Evaluator set at its fitted value
    untestable: tuple = ()     # effects no target can show (not run)


@dataclass(frozen=True)
class LoopRun:
    """One loop run: what it was asked (settings, targets) and what it found."""
    settings: dict             # the config's loop section
    targets: Targets
    plain: PlainModel
    selection: Selection
    base: dict                 # the plain model's material parameters ({}: Table 4.2's)
    minutes: float             # wall time of this run
    likelihood_dof: float      # the likelihood's t degrees of freedom (select.residual_dof)
    long_term_law: object = None   # horizon.LongTermLaw the measured curves chose; None: none given
    mapping: dict = None       # {test: the stress mapping's record} (scenario.mapping); None: none
    noise: object = None       # select.NoiseModel every model was judged under

    @property
    def cycles(self):
        """The simulated load cycles N = 1 .. cycles (the DEM horizon)."""
        return np.arange(1, self.settings["cycles"] + 1, dtype=float)

    @property
    def cases(self):
        """K: the specimens, each run under every test by every model."""
        return self.plain.runs["curves"].shape[1]

    @property
    def dem_cases(self):
        """DEM cases behind the outputs (some may have come from the cache)."""
        sets = (1 + (self.plain.probe is not None)
                + sum(len(c.evaluate.sets) for c in self.selection.candidates.values()))
        return self.cases * len(self.targets.points) * sets

    @property
    def dem_runs(self):
        """Distinct case files behind them: cases of one scenario key are one run (tests
        that differ only in what does not act, a quasi-static test's f)."""
        return len({str(f) for st in self._evaluated_sets() for per_test in st["cases"] for f in per_test})

    @property
    def dem_first_loadings(self):
        """Distinct first loadings (cycle 0) behind those runs: runs that differ only in
        what cycle 0 does not read (a real-time test's f) or in effects that act from its
        end (hook-only: abrasion, when the loop shares the first loading) go on from one."""
        return self.cases * len({key for st in self._evaluated_sets() for key in st["first_loadings"]})

    def _evaluated_sets(self):
        """Every evaluated set (Evaluator.sets' entries): the plain model's, its probe's, the candidates'."""
        return [self.plain.runs, *([self.plain.probe] if self.plain.probe else []),
                *(st for c in self.selection.candidates.values() for st in c.evaluate.sets)]
