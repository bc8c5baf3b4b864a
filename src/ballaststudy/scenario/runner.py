"""The one runner: (scenario, specimen k) -> a metrics file. A fresh case loads its assembled
specimen, takes the scenario's rig parameters, applies its modifiers in order (and the
chaos probe's perturbation), then runs the cycles; a case with a checkpoint beside its
output resumes from it (the modifiers' effects live in the checkpointed state, only their
end-of-cycle hooks are attached again). ``run_cases`` runs many in a pool (cluster.pool:
processes here, or a Dask cluster's workers), or all at once as one GPU batch (backend ``cuda``: rig.batched), and skips finished ones, so
an interrupted calibration or loop resumes.

Given a cache folder to share the first loading in (``shared``), a case of the plain model
(material modifiers only) keeps its state at the end of cycle 0 beside its file, and a
scenario with hook-only modifiers (abrasion: they first act at cycle 0's end) starts from
that state of the scenario without them - run once for all their values, where a specimen
that gives way in its first loading costs most - with their hooks for the cycles it ended:
the same bytes as a run of its own. (Only the plain model keeps it: the loop adds one
effect at a time, and a state is as large as its case file, 37 MB where a small specimen
gave way.)

Cases that differ only in what cycle 0 does not read (one ``first_cycle_key``: a real-time
test's frequency) run their cycle 0 once: ``run_cases`` runs it first, keeps its state
until they are done (``first_cycle_state``), and each goes on from there under its own
parameters (BiaxialRun.continue_under): the same bytes as a run of its own, and where the
specimen gives way in its first loading the whole run is one. (Both on the cpu backend.)"""
import json
import os
from dataclasses import replace
from pathlib import Path

from numba.core import config as numba_config
from tqdm import tqdm

from ..cluster.guard import checkpoint_guard
from ..cluster.pool import LocalPool
from ..dem.gpu import cuda_available
from ..inputs import open_netcdf
from ..rig.batched import run_batched
from ..rig.kinds import kind_of, rig_classes
from ..schema import ConfigError
from ..stones import stone_model
from .modifiers import MODIFIERS

BACKENDS = ("cpu", "cuda")


def cached_case(root, scenario, k):
    """Where the runner keeps case ``k`` of a scenario under a cache folder: <key>/case<k>.nc."""
    return Path(root) / scenario.key / f"case{k}.nc"


def checkpoint_of(out):
    return Path(out).with_name(Path(out).stem + ".checkpoint.npz")


def first_loaded(root, scenario, k):
    """Where case ``k`` of a scenario keeps its state at the end of cycle 0 (or where its
    specimen gave way before): beside its case file."""
    return cached_case(root, scenario, k).with_suffix(".first_loaded.npz")


def keeps_first_loading(scenario):
    """Whether hook-only effects start from its state: the plain model's cases."""
    return all(MODIFIERS[name].role == "material" for name, _ in scenario.modifiers)


def without_hook_only(scenario):
    """The scenario without its hook-only modifiers (its run up to the end of cycle 0);
    None when it has none."""
    kept = tuple((n, v) for n, v in scenario.modifiers if not MODIFIERS[n].hook_only)
    return replace(scenario, modifiers=kept) if len(kept) < len(scenario.modifiers) else None


def first_cycle_state(case):
    """Where the cycle-0 state of a case (scenario, k, out) is kept while the cases that
    share it run: beside the cache folder of its output's scenario."""
    scenario, k, out = case
    return Path(out).parent.parent / f"{scenario.first_cycle_key}.first_cycle" / f"case{k}.npz"


def _hooks(scenario):
    return [h for name, values in scenario.modifier_values() for h in MODIFIERS[name].hooks(values)]


def fresh_run(scenario, k, checkpoint, checkpoint_every=None):
    """The run of case ``k`` from its assembled specimen, the modifiers applied."""
    assembled = open_netcdf(scenario.specimens[k], "assembled")
    if kind_of(assembled) != scenario.kind:
        raise ValueError(f"{scenario.specimens[k]}: a {kind_of(assembled)} specimen in a {scenario.kind} scenario")
    rig_class, run_class, _ = rig_classes(scenario.kind)
    rig = rig_class.from_dataset(assembled, "engine_checkpoint")
    rig.params = scenario.rig
    # each specimen's strengths from its own seed: one specimen, the same stones under
    # every parameter set (common random numbers across a calibration's sets)
    rig.use_stone_model(scenario.stone_model, scenario.splitting_for(rig.layout.seed))
    for name, values in scenario.modifier_values():
        MODIFIERS[name].apply(rig, values, scenario.covariates)
    if scenario.perturbation_m_s:       # the chaos probe (loop.select)
        rig.sim.perturb_velocities(scenario.perturbation_m_s, scenario.perturbation_seed + k)
    return run_class(rig, scenario.cycles, checkpoint=checkpoint, checkpoint_every=checkpoint_every,
                     metrics=scenario.metrics)


def prepared_run(scenario, k, out, checkpoint_every=None, restart=False):
    """(run, resumed): case ``k`` resumed from the checkpoint beside ``out`` (unless
    ``restart``) or fresh, with the modifiers' end-of-cycle hooks attached."""
    ckpt = checkpoint_of(out)
    resumed = ckpt.is_file() and not restart
    if resumed:
        run_class = rig_classes(scenario.kind)[1]
        run = run_class.from_checkpoint(ckpt, cycles=scenario.cycles, checkpoint_every=checkpoint_every)
    else:
        run = fresh_run(scenario, k, ckpt, checkpoint_every)
    run.hooks += _hooks(scenario)
    return run, resumed


def _from_first_loading(prefix, scenario, k, out, shared):
    """Case ``k`` of ``scenario`` from the state of ``prefix`` (without_hook_only) at the
    end of cycle 0 (run here if no case has kept it), its hooks called for the cycles that
    state ended, then attached; it checkpoints beside ``out``."""
    state = first_loaded(shared, prefix, k)
    run_first_cycle(prefix, k, state)
    run = rig_classes(scenario.kind)[1].from_checkpoint(state, cycles=scenario.cycles)
    run.checkpoint = checkpoint_of(out)
    hooks = _hooks(scenario)
    for cycle in range(run.s.cycle):
        for hook in hooks:
            hook(run, cycle)
    run.hooks += hooks
    return run


def run_first_cycle(scenario, k, state):
    """Case ``k`` of ``scenario`` fresh up to the end of cycle 0 (or where its specimen gave
    way before), its hooks called there, the state saved in ``state``."""
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    if Path(state).is_file():
        return
    run = fresh_run(scenario, k, None)
    run.hooks += _hooks(scenario)
    run.run(stop_after=1)
    Path(state).parent.mkdir(parents=True, exist_ok=True)
    run.save_checkpoint(state)


def _from_first_cycle(scenario, k, out, state):
    """Case ``k`` of ``scenario`` from ``state`` (run_first_cycle's of a scenario of the same
    first_cycle_key) under its own parameters, its hooks attached; None if the state
    cannot go on under them (BiaxialRun.continue_under's ValueError)."""
    run = rig_classes(scenario.kind)[1].from_checkpoint(state, cycles=scenario.cycles)
    params = replace(run.rig.params, **{key: getattr(scenario.rig, key)
                                        for key in run.rig.params.first_cycle_inert_keys()})
    try:
        run.continue_under(params)
    except ValueError:
        return None
    run.checkpoint = checkpoint_of(out)
    run.hooks += _hooks(scenario)
    return run


def write_case(run, scenario, k, out, figures=False, attrs=None):
    """The metrics file of a finished run, saying what made it."""
    write_outputs = rig_classes(scenario.kind)[2]
    write_outputs(run, out, figures=figures, attrs={
        "assembled_file": scenario.specimens[k],
        **({"measured_conditions_file": scenario.conditions_file} if scenario.conditions_file else {}),
        "scenario_key": scenario.key,
        "modifiers_json": json.dumps(scenario.modifier_values()),
        "material_parameters_json": json.dumps(scenario.material_values()),     # {}: Table 4.2's
        **scenario.mapping,         # the stress mapping the test's q bounds went through
        "numba_cpu_target": numba_config.CPU_NAME or "host",   # NUMBA_CPU_NAME: what the bits hold on
        **(attrs or {})})


def run_case(scenario, k, out, shared=None, start=None):
    """Case ``k`` of ``scenario`` into ``out`` (resuming; a finished one is kept), sharing
    the first loading in the cache folder ``shared`` (None: not), or going on from the
    cycle-0 state ``start`` (run_first_cycle's; None: none). Returns out."""
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    out = Path(out)
    if out.is_file():
        return str(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    prefix = without_hook_only(scenario) if shared else None
    resumed = checkpoint_of(out).is_file()
    run = None
    if prefix and not resumed:
        run = _from_first_loading(prefix, scenario, k, out, shared)
    elif start and not resumed:
        run = _from_first_cycle(scenario, k, out, start)
    if run is None:
        run, resumed = prepared_run(scenario, k, out)
    guard = checkpoint_guard(f"case {k} of {scenario.key}")
    if guard:
        run.hooks.append(guard)
    if shared and not resumed and not prefix and keeps_first_loading(scenario):
        if run.s.cycle == 0:
            run.run(stop_after=1)
        run.save_checkpoint(first_loaded(shared, scenario, k))
    run.run()
    write_case(run, scenario, k, out)
    checkpoint_of(out).unlink(missing_ok=True)
    return str(out)


def check_backend(backend):
    """Refuse a backend this machine cannot run, in one line (before any work)."""
    if backend not in BACKENDS:
        raise ConfigError("command line", "--backend", f"{backend!r}: one of {', '.join(BACKENDS)}")
    if backend == "cuda" and not cuda_available():
        raise ConfigError("command line", "--backend", "cuda: numba sees no CUDA GPU here "
                          "(a machine with one, and pip install -e '.[cuda]'), or use cpu")


def run_cases(cases, jobs=1, progress=False, desc="cases", backend="cpu", shared=None, pool=None):
    """Every (scenario, k, out) in ``cases``, each ``out`` once (scenarios of one key share
    their cases): in ``pool`` (cluster.pool; None: ``jobs`` processes here) on the cpu
    (cycle 0 run once for cases of one first_cycle_key, and the first loading shared in the
    cache folder ``shared``, see above), or every unfinished case in GPU batches, one per
    contact law (cuda)."""
    check_backend(backend)
    if backend == "cuda" and not all(stone_model(c[0].stone_model).gpu_batch for c in cases):
        raise ConfigError("config", "stone_model", "the GPU batch (backend cuda) runs bonded "
                          "stones only (no per-clump timestep or clump density scaling on the "
                          "device yet); allowed: stone_model bonded, or backend cpu")
    unique = {}
    for case in cases:
        unique.setdefault(str(case[2]), case)
    cases = list(unique.values())
    bar = tqdm(total=len(cases), desc=desc, unit="case", disable=not progress)
    if backend == "cuda":
        _run_on_gpu(cases, bar)
    else:
        starts = _shared_first_cycles(cases, shared)
        firsts = {state: case for case, state in zip(cases, starts) if state and not state.is_file()}
        pool = pool or LocalPool(jobs)
        pool.map(run_first_cycle, [(c[0], c[1], state) for state, c in firsts.items()])
        pool.map(run_case, [(*c, shared, start) for c, start in zip(cases, starts)], bar.update,
                 progress=lambda call: checkpoint_stamp(call[2]))
        for state in {s for s in starts if s}:
            state.unlink(missing_ok=True)
            if state.parent.is_dir() and not any(state.parent.iterdir()):
                state.parent.rmdir()
    bar.close()


def _shared_first_cycles(cases, shared):
    """Per case, the cycle-0 state it goes on from (first_cycle_state), or None: cases that
    are not finished, resuming or starting from a shared first loading (hook-only
    modifiers) and share their first_cycle_key with another, or whose state is kept from an
    interrupted call."""
    def free(case):
        scenario, _, out = case
        return not (Path(out).is_file() or checkpoint_of(out).is_file()
                    or (shared and without_hook_only(scenario)))
    states = [first_cycle_state(c) if free(c) else None for c in cases]
    count = {}
    for state in states:
        count[state] = count.get(state, 0) + 1
    return [s if s and (count[s] > 1 or s.is_file()) else None for s in states]


def checkpoint_stamp(out):
    """(size, mtime) of the checkpoint beside ``out``, None without one: it changes as the
    case gets on (cluster.pool resubmits a case lost with its workers while it does)."""
    try:
        st = checkpoint_of(out).stat()
    except OSError:
        return None
    return st.st_size, st.st_mtime_ns


def _run_on_gpu(cases, bar):
    """The unfinished cases prepared (resumed or fresh) as run_case does, stepped together
    (rig.batched.run_batched), each written as soon as it finishes."""
    todo, where = {}, {}
    for scenario, k, out in cases:
        out = Path(out)
        if out.is_file():
            bar.update()
            continue
        out.parent.mkdir(parents=True, exist_ok=True)
        run, _ = prepared_run(scenario, k, out)
        todo.setdefault(run.rig.sim.law.layout(), []).append(run)
        where[id(run)] = (scenario, k, out)

    def job(run):
        scenario, k, out = where[id(run)]
        run.run()
        write_case(run, scenario, k, out)
        checkpoint_of(out).unlink(missing_ok=True)
        bar.update()

    for runs in todo.values():
        run_batched(runs, job)
