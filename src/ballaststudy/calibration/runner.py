"""The model a calibration (or the loop, issue 14) evaluates: one parameter set = K cases,
the same K assembled specimens (biaxial for triaxial/biaxial tests, box for box tests)
loaded under the measured test's conditions with the set's parameters - material
parameters (calibration.parameters), or an effect's (loop.effects) on top of fixed ones.
Cases run in parallel processes; each finished case is a metrics.nc under
``cases/<hash of the set>/case<k>.nc`` (with its checkpoint while it runs), so an
interrupted calibration resumes without repeating finished cases.

The simulated curve of cycle k (0-based) is the measured N = k + 1 (cycle 0 is the first
loading); it is compared at the measured points N <= cycles, interpolated in ln N. A case
that failed (its strain ran away, ``metrics.nc`` attribute ``failed``) has no rows past its
failure: its strain there is censored at the failure strain (at least that, or its last
value if larger) - a set that fails the specimen fits a measured curve that did not fail
badly, as it should."""
import hashlib
import json
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
from tqdm import tqdm

from ..inputs import open_netcdf


def set_key(values, context):
    """A short hash of a parameter set (rounded to 12 significant digits) and what else
    decides its cases (cycles, conditions, specimens, config): the cache folder's name."""
    text = json.dumps({"values": {k: float(f"{v:.12g}") for k, v in sorted(values.items())},
                       **context}, sort_keys=True)
    return hashlib.sha1(text.encode()).hexdigest()[:12]


def run_case(job):
    """One case: load the assembled specimen, apply the parameters and the rig's parameters
    (the config's with the test's conditions), run
    ``cycles`` cycles (resuming from its checkpoint), write metrics.nc. Returns its path."""
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    from ..loop.effects import hooks, switch_on
    from ..measured.importer import load_conditions
    from ..rig.kinds import kind_of, params_class, rig_classes
    from .parameters import apply_parameters
    out = Path(job["out"])
    if out.is_file():
        return str(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ckpt = out.with_name(out.stem + ".checkpoint.npz")
    assembled = open_netcdf(job["specimen"], "assembled")
    rig_class, run_class, write_outputs = rig_classes(kind_of(assembled))
    if ckpt.is_file():
        run = run_class.from_checkpoint(ckpt, cycles=job["cycles"])
    else:
        rig = rig_class.from_dataset(assembled, "engine_checkpoint")
        rig.params = params_class(kind_of(assembled))(**job["rig"])
        apply_parameters(rig, job["values"])
        if job["effect"]:
            switch_on(job["effect"], rig, job["effect_values"], load_conditions(job["conditions"]))
        if job.get("perturbation_m_s"):         # the chaos probe (loop.select)
            rig.sim.perturb_velocities(job["perturbation_m_s"], job["perturbation_seed"])
        run = run_class(rig, job["cycles"], checkpoint=ckpt, metrics=job["metrics"])
    if job["effect"]:                   # hooks are not in a checkpoint: again on resume
        run.hooks += hooks(job["effect"], job["effect_values"])
    run.run()
    write_outputs(run, out, figures=False, attrs={
        "assembled_file": str(job["specimen"]), "measured_conditions_file": str(job["conditions"]),
        "calibration_parameters_json": json.dumps(job["values"]),
        "effect": job["effect"] or "none", "effect_parameters_json": json.dumps(job["effect_values"])})
    ckpt.unlink(missing_ok=True)
    return str(out)


def case_curve(metrics_path, quantity, cycles):
    """(cycles,) curve of a case; a failed case's missing cycles censored (module doc)."""
    ds = open_netcdf(metrics_path, "metrics")
    rows = ds[quantity].values if quantity in ds else np.zeros(0)
    curve = np.empty(cycles)
    curve[:rows.size] = rows[:cycles]
    if rows.size < cycles:
        if not ds.attrs.get("failed"):
            raise ValueError(f"{metrics_path}: {rows.size} of {cycles} cycles and not failed")
        prm = json.loads(ds.attrs["rig_params_json"])
        last = rows[-1] if rows.size else -np.inf
        curve[rows.size:] = max(prm["failure_axial_strain"], last)
    return curve, bool(ds.attrs.get("failed"))


def at_points(curve, points):
    """The curve of cycles N = 1..len(curve) at the measured N (1 <= N <= len), in ln N."""
    n = np.arange(1, curve.size + 1, dtype=float)
    return np.interp(np.log(points), np.log(n), curve)


class Evaluator:
    """``evaluate(thetas) -> [(K, P) curves at the measured points]`` for calibrate(): every
    set runs the K specimens under each target test's conditions; the P points are the tests'
    measured points one after the other. Keeps every set's folder, its full curves
    (T, K, cycles) and failures (``self.sets``)."""

    def __init__(self, names, specimens, tests, config, cycles, quantity, out_dir, jobs=1,
                 progress=False, effect=None, base=None, perturbation_m_s=0.0, perturbation_seed=0):
        """tests: [(conditions YAML, measured N within the cycles)], one per target;
        ``names``: the parameters varied - material ones, or ``effect``'s (loop.effects)
        with the material parameters fixed at ``base`` ({name: value}; {}: Table 4.2's);
        ``perturbation_m_s`` > 0: every case starts from its specimen's velocities perturbed
        by that much (Simulation.perturb_velocities, seeded by ``perturbation_seed`` + the
        case index): the chaos probe of loop.select."""
        from ..config import load_config
        from ..measured.importer import load_conditions
        from ..rig.kinds import kind_of, params_from_config
        self.names, self.specimens = list(names), [str(s) for s in specimens]
        self.cycles, self.quantity = int(cycles), quantity
        self.out_dir, self.jobs, self.progress = Path(out_dir), int(jobs), progress
        self.kind = kind_of(open_netcdf(self.specimens[0], "assembled"))
        # read once (or given, loaded, by a caller making several Evaluators): a config
        # edited meanwhile changes nothing
        cfg = config if isinstance(config, dict) else load_config(config)
        self.metrics = cfg.get("metrics")
        self.tests = []
        for conditions, points in tests:
            params = params_from_config(self.kind, cfg.get("rig", {}))
            loaded = load_conditions(conditions)
            params.take_conditions(loaded)
            self.tests.append(dict(conditions=str(conditions), points=np.asarray(points, float),
                                   rig=params.to_dict(), covariates=loaded.get("covariates") or {}))
        self.effect, self.base = effect, dict(base or {})
        self.perturbation_m_s, self.perturbation_seed = float(perturbation_m_s), int(perturbation_seed)
        # the covariates too: an effect may act through one (fouling through VCI), and a
        # test's VCI edited must not reuse cases run at the old one
        self.context = {"cycles": self.cycles, "rig": [t["rig"] for t in self.tests],
                        "covariates": [t["covariates"] for t in self.tests],
                        "metrics": self.metrics, "effect": effect, "base": self.base,
                        "specimens": [Path(s).name for s in self.specimens],
                        # only when on: the unperturbed sets keep their cache keys
                        **({"perturbation_m_s": self.perturbation_m_s} if self.perturbation_m_s else {}),
                        **({"perturbation_seed": self.perturbation_seed} if self.perturbation_seed else {})}
        self.sets = []

    def jobs_for(self, values):
        key = set_key(values, self.context)
        # the fixed material parameters under every set: an effect's on top of them, and the
        # plain model (no effect, nothing varied) is the model at them, not Table 4.2's
        material, effect_values = (self.base, values) if self.effect else ({**self.base, **values}, {})
        return key, [[dict(specimen=s, values=material, cycles=self.cycles, rig=t["rig"],
                           effect=self.effect, effect_values=effect_values,
                           metrics=self.metrics, conditions=t["conditions"],
                           perturbation_m_s=self.perturbation_m_s,
                           perturbation_seed=self.perturbation_seed + k,
                           out=str(self.out_dir / "cases" / key / f"test{j}" / f"case{k}.nc"))
                      for k, s in enumerate(self.specimens)] for j, t in enumerate(self.tests)]

    def _run(self, jobs, n_sets):
        bar = tqdm(total=len(jobs), desc=f"{n_sets} parameter set(s)", unit="case",
                   disable=not self.progress)
        if self.jobs > 1 and len(jobs) > 1:
            with ProcessPoolExecutor(self.jobs) as pool:
                for done in as_completed([pool.submit(run_case, j) for j in jobs]):
                    done.result()
                    bar.update()
        else:
            for j in jobs:
                run_case(j)
                bar.update()
        bar.close()

    def __call__(self, thetas):
        batch = [dict(zip(self.names, map(float, t))) for t in np.atleast_2d(thetas)]
        keyed = [self.jobs_for(v) for v in batch]
        self._run([j for _, per_test in keyed for js in per_test for j in js], len(batch))
        out = []
        for values, (key, per_test) in zip(batch, keyed):
            read = [[case_curve(j["out"], self.quantity, self.cycles) for j in js] for js in per_test]
            curves = np.array([[c for c, _ in r] for r in read])              # (T, K, cycles)
            at = np.concatenate([[at_points(c, t["points"]) for c in curves[j]]
                                 for j, t in enumerate(self.tests)], axis=1)       # (K, P)
            self.sets.append(dict(values=values, key=key, curves=curves, at_points=at,
                                  failed=[[f for _, f in r] for r in read]))
            out.append(at)
        return out
