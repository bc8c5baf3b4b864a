"""The model a calibration (or the loop) evaluates: one parameter set = one scenario per
target test, each the same K assembled specimens (biaxial for triaxial/biaxial tests, box
for box tests) under that test's conditions with the set's modifiers - material parameters,
or an effect's on top of fixed material ones. The scenario runner runs the cases in
parallel processes and caches each under ``cases/<scenario key>/case<k>.nc``, so an
interrupted calibration resumes without repeating finished cases; the curves are compared
at the measured points N <= cycles (scenario.results)."""
from pathlib import Path

import numpy as np

from ..config import load_config
from ..inputs import open_netcdf
from ..measured.importer import load_conditions, measured_test_name
from ..rig.kinds import kind_of
from ..scenario.modifiers import material_modifiers
from ..scenario.results import at_points, case_curve
from ..scenario.runner import cached_case, run_cases, without_hook_only
from ..scenario.scenario import conditioned_rig, scenario, splitting_of
from ..stones import DEFAULT


class Evaluator:
    """``evaluate(thetas) -> [(K, P) curves at the measured points]`` for calibrate(): every
    set runs the K specimens under each target test's conditions; the P points are the tests'
    measured points one after the other. Keeps every set's scenarios, its case files, full
    curves (T, K, cycles) and failures (``self.sets``)."""

    def __init__(self, names, specimens, tests, config, cycles, quantity, out_dir, jobs=1,
                 progress=False, effect=None, base=None, perturbation_m_s=0.0, perturbation_seed=0,
                 backend="cpu", mapping=None, share_first_loading=False, pool=None):
        """tests: [(conditions YAML, measured N within the cycles)], one per target;
        ``names``: the parameters varied - material ones, or ``effect``'s (a modifier)
        with the material parameters fixed at ``base`` ({name: value}; {}: Table 4.2's);
        ``perturbation_m_s`` > 0: every case starts from its specimen's velocities perturbed
        by that much (Simulation.perturb_velocities, seeded by ``perturbation_seed`` + the
        case index): the chaos probe of loop.select. ``backend``: run_cases' (cpu, cuda);
        ``pool``: where the cpu cases run (cluster.pool; None: ``jobs`` processes here).
        ``mapping``: the stress mapping of the tests' q onto the specimens (scenario.mapping;
        None: none), the same for every set. ``share_first_loading``: the plain model's cases keep
        their state after cycle 0 in the cache, and a set of a hook-only effect (abrasion)
        starts there (scenario.runner; the loop, whose plain set runs first)."""
        self.names, self.specimens = list(names), [str(s) for s in specimens]
        self.cycles, self.quantity = int(cycles), quantity
        self.cache, self.jobs, self.progress = Path(out_dir) / "cases", int(jobs), progress
        self.backend, self.pool = backend, pool
        self.shared = self.cache if share_first_loading else None
        self.kind = kind_of(open_netcdf(self.specimens[0], "assembled"))
        # read once (or given, loaded, by a caller making several Evaluators): a config
        # edited meanwhile changes nothing
        cfg = config if isinstance(config, dict) else load_config(config)
        self.metrics = cfg.get("metrics")
        self.stone_model = cfg.get("stone_model", DEFAULT)
        self.splitting = splitting_of(cfg)
        self.tests = []
        for conditions, points in tests:
            loaded = load_conditions(conditions)
            rig, record = conditioned_rig(self.kind, cfg.get("rig", {}), loaded, conditions_file=conditions,
                                          mapping=mapping)
            self.tests.append(dict(conditions=str(conditions), points=np.asarray(points, float), loaded=loaded,
                                   rig=rig, mapping=record))
        self.effect, self.base = effect, dict(base or {})
        self.perturbation_m_s, self.perturbation_seed = float(perturbation_m_s), int(perturbation_seed)
        self.sets = []

    def scenarios(self, values):
        """One scenario per test for a parameter set {name: value}. The fixed material
        parameters under every set: an effect's on top of them, and the plain model (no
        effect, nothing varied) is the model at them, not Table 4.2's."""
        if self.effect:
            modifiers = material_modifiers(self.base) + [(self.effect, values)]
        else:
            modifiers = material_modifiers({**self.base, **values})
        return [scenario(self.kind, self.specimens, t["rig"], self.cycles, modifiers, t["loaded"],
                         t["conditions"], self.metrics, self.perturbation_m_s, self.perturbation_seed,
                         t["mapping"], self.stone_model, self.splitting)
                for t in self.tests]

    def mapping_records(self):
        """{test (source/name): its stress mapping's record}."""
        return {measured_test_name(t["conditions"]): t["mapping"] for t in self.tests}

    def _first_loading(self, scenario):
        """The key of the cycle 0 a scenario's cases go on from (run_cases on the cpu: a
        real-time test's f apart; sharing the first loading, its hook-only modifiers apart;
        on the GPU each its own)."""
        if self.backend == "cuda":
            return scenario.key
        return ((self.shared and without_hook_only(scenario)) or scenario).first_cycle_key

    def __call__(self, thetas):
        batch = [dict(zip(self.names, map(float, t))) for t in np.atleast_2d(thetas)]
        per_set = [self.scenarios(v) for v in batch]
        files = [[[cached_case(self.cache, s, k) for k in range(len(self.specimens))] for s in scs]
                 for scs in per_set]
        run_cases([(s, k, f[j][k]) for scs, f in zip(per_set, files) for j, s in enumerate(scs)
                   for k in range(len(self.specimens))], self.jobs, self.progress,
                  f"{len(batch)} parameter set(s)", self.backend, self.shared, self.pool)
        out = []
        for values, scs, f in zip(batch, per_set, files):
            read = [[case_curve(p, self.quantity, self.cycles) for p in per_test] for per_test in f]
            curves = np.array([[c for c, _ in r] for r in read])              # (T, K, cycles)
            at = np.concatenate([[at_points(c, t["points"]) for c in curves[j]]
                                 for j, t in enumerate(self.tests)], axis=1)       # (K, P)
            self.sets.append(dict(values=values, keys=[s.key for s in scs], first_loadings=[
                                      self._first_loading(s) for s in scs], cases=f, curves=curves,
                                  at_points=at, failed=[[fl for _, fl in r] for r in read]))
            out.append(at)
        return out
