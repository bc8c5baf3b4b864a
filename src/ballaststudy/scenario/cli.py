"""`ballaststudy case ...`: assemble a case of the configured rig (``rig.kind``: the box
test or the cyclic biaxial test; ``--rig`` overrides) from a BPM library, and run one: a
one-specimen scenario - the assembled case under the config's rig parameters, optionally a
measured test's conditions, a biaxial loading mode and calibrated material values -
through the scenario runner.

    ballaststudy case assemble BPM.nc --case K --out results/cases/DB/caseK/assembled.nc
    ballaststudy case run ASSEMBLED.nc --cycles N --out results/cases/DB/caseK/metrics.nc
        [--conditions TEST.yaml] [--mode real_time] [--parameters calibrated.yaml]

``register(subparsers)`` adds the ``case`` stage to the main parser (wired in cli.py). It
lives here, above the rigs and the config, because it reads the config and runs scenarios."""
import argparse
import sys
import time
from pathlib import Path

from tqdm import tqdm

from ..argtypes import SEED, add_config, add_quiet, integer, number
from ..atomic import atomic_path
from ..config import ConfigError, load_config
from ..inputs import open_netcdf, writable_dir, writable_file
from ..measured.importer import load_conditions
from ..provenance import Recorder
from ..rig.assembly import assemble
from ..rig.biaxial import BiaxialRig, assemble_biaxial
from ..rig.biaxial.strength import run_strength, strength_dataset, strength_envelope
from ..rig.kinds import kind_of, params_from_config
from ..rig.library import load_library
from ..rig.params import case_seed
from ..rig.vtk import vtk_hook
from .modifiers import EFFECTS, MODIFIERS, ModifierError, load_material_values, material_modifiers
from .mapping import stage_mapping
from .runner import checkpoint_of, prepared_run, write_case
from ..stones import STONE_MODELS
from .scenario import check_stone_model, conditioned_rig, scenario, splitting_of


def _kind(args, cfg):
    return getattr(args, "rig", None) or cfg["rig"].get("kind", "box")


def _params(args):
    cfg = load_config(args.config)
    return cfg, params_from_config(_kind(args, cfg), cfg.get("rig", {}))


def _case_assemble(args):
    writable_file(args.out)
    cfg, params = _params(args)
    biaxial = _kind(args, cfg) == "biaxial"
    build = assemble_biaxial if biaxial else assemble
    for key in ("width_m", "height_m", "membrane_segments"):       # a specimen other than the config's
        if getattr(args, key) is not None:
            if not biaxial:
                raise ConfigError(args.config, "rig.kind", f"{_kind(args, cfg)}: --{key.replace('_', '-')} is for a biaxial specimen")
            setattr(params, key, getattr(args, key))
    lib = load_library(args.library)
    seed = args.seed if args.seed is not None else case_seed(cfg["seed"], lib.database, args.case)
    recorder = Recorder("case assemble", inputs=(args.library, args.config),
                        params={"case": args.case, "rig": params.to_dict()}, seed=seed)
    t0 = time.time()
    bar = tqdm(desc=f"assemble {lib.database} case {args.case}", unit="step", disable=args.quiet,
               unit_scale=True)
    rig = build(lib, params, seed, progress=bar.update)
    bar.close()
    rig.save(args.out, attrs={"case": args.case, "library_file": str(args.library),
                              "assembly_seconds": round(time.time() - t0, 1)})
    recorder.finish()
    recorder.write_beside(args.out)
    lay = rig.layout
    for line in lay.stages_at_limit:     # the run goes on; the log and the file say so
        print(f"ballaststudy: warning: {args.out}: {line}", file=sys.stderr)
    if not args.quiet:
        print(f"wrote {args.out}: {len(lay.stone_library_index)} stones, "
              f"{rig.stone_balls().size} balls, {lay.bonds_installed} bonds, "
              f"steps {lay.stage_steps}")


def case_scenario(args):
    """(scenario, material values) of ``case run``'s arguments; ConfigError naming the file
    whose value does not fit."""
    kind = kind_of(open_netcdf(args.assembled, "assembled"))
    if args.mode and kind != "biaxial":
        raise ConfigError(args.assembled, None, "--mode needs a biaxial case")
    cfg = load_config(args.config)
    conditions = load_conditions(args.conditions) if args.conditions else None
    if conditions is None and args.strength_envelope:     # the mapping maps a test's q
        raise ConfigError("command line", "--strength-envelope", "maps a measured test's q: it "
                          "needs --conditions")
    mapping = stage_mapping(cfg, args.config, args.strength_envelope, kind) if conditions else None
    rig, record = conditioned_rig(kind, cfg.get("rig", {}), conditions, args.mode, args.conditions, mapping)
    material = load_material_values(args.parameters) if args.parameters else {}
    model = check_stone_model(cfg, args.config, "cpu", args.stone_model, (args.parameters, material), stages=())
    splitting = splitting_of(cfg)
    effects = [_effect(text, model, splitting) for text in args.effect or ()]
    return scenario(kind, [args.assembled], rig, args.cycles, material_modifiers(material) + effects,
                    conditions, args.conditions or "", cfg.get("metrics"), mapping=record, stone_model=model,
                    splitting=splitting), material


def _effect(text, model, splitting):
    """(name, {parameter: value}) of an --effect NAME:PARAMETER=VALUE,... that the stone
    model can take; ConfigError naming the option otherwise."""
    name, _, rest = text.partition(":")
    def bad(why):
        return ConfigError("command line", "--effect", f"{text}: {why}")
    if name not in EFFECTS:
        raise bad(f"not an effect; allowed: {', '.join(EFFECTS)}")
    try:
        values = {k.strip(): float(v) for k, v in (item.split("=") for item in rest.split(",") if item)}
        MODIFIERS[name].check(values)
    except ValueError as err:
        raise bad(f"{err}; expected {name}:" + ",".join(f"{p.name}=VALUE" for p in MODIFIERS[name].parameters)) from None
    m = MODIFIERS[name]
    if m.needs_flat_joints and not STONE_MODELS[model].has_flat_joints:
        raise bad(f"acts on flat joints, which stone_model {model} has not")
    if m.needs_splitting and splitting is None:
        raise bad("acts on splitting stones; allowed with stone_model rigid and rigid_stones.splitting true")
    return name, values


def _progress(bar, first):
    last = [first, None]

    def progress(phase, cycle):
        if cycle != last[0]:
            bar.update(cycle - last[0])
            last[0] = cycle
        if phase != last[1]:
            last[1] = phase
            bar.set_postfix_str(phase)
    return progress


def _case_run(args):
    out = writable_file(args.out)
    ckpt = writable_file(checkpoint_of(out))
    sc, material = case_scenario(args)
    recorder = Recorder("case run", inputs=(args.assembled, args.config,
                                            *[p for p in (args.conditions, args.parameters,
                                                          args.strength_envelope) if p]),
                        params={"cycles": args.cycles, "rig": sc.rig.to_dict(), "metrics": sc.metrics,
                                "material_parameters": material, "stress_mapping": sc.mapping,
                                "stone_model": sc.stone_model, "splitting": sc.splitting,
                                "effects": [[n, v] for n, v in sc.modifier_values() if n in EFFECTS],
                                "scenario_key": sc.key})
    try:
        run, resumed = prepared_run(sc, 0, out, args.checkpoint_every, args.restart)
    except ModifierError as err:          # a calibrated value this specimen cannot take
        raise ConfigError(args.parameters, f"parameters.{err.name}", err.reason) from None
    except (ValueError, KeyError, TypeError) as err:
        raise ConfigError(args.assembled, None, f"not an assembled case ({err})") from None
    if resumed and not args.quiet:
        print(f"resuming from {ckpt} (cycle {run.s.cycle}, step {run.rig.sim.step})")
    vtk_dir = None if args.no_vtk else writable_dir(out.with_name("vtk"))
    if vtk_dir is not None:
        run.hooks.append(vtk_hook(vtk_dir, sc.rig.vtk_cycles, args.cycles))
    bar = tqdm(total=args.cycles, initial=run.s.cycle, desc="cycles", unit="cycle", disable=args.quiet)
    try:
        run.run(progress=_progress(bar, run.s.cycle), stop_after=args.stop_after)
    except RuntimeError as err:      # a stage that does not converge: say where, exit 2
        kept = f" (checkpoint kept: {ckpt})" if ckpt.exists() else ""
        raise ConfigError(args.assembled, "rig", f"{err}{kept}") from None
    finally:
        bar.close()
    if run.s.phase != "done":
        print(f"stopped after cycle {run.s.cycle} (checkpoint {ckpt})", file=sys.stderr)
        return
    source = f"calibrated ({args.parameters})" if material else "table_4_2"
    write_case(run, sc, 0, out, figures=not args.no_figures, attrs={"material_parameters": source})
    if getattr(run.s, "failure", ""):     # a result (recorded in the file), not an error
        print(f"ballaststudy: note: {out}: {run.s.failure} (after {run.s.cycle} cycles)", file=sys.stderr)
    recorder.finish()
    figures = [] if args.no_figures else [out.with_name("case.png"), out.with_name("behaviours.png")]
    vtk = sorted(p for p in vtk_dir.rglob("*") if p.is_file()) if vtk_dir is not None else []
    kept = [p for p in (*figures, ckpt) if p.is_file()]     # the checkpoint: to extend the run later
    recorder.write_beside(out, also=kept + vtk)
    if not args.quiet:
        print(f"wrote {out}")


def _case_strength(args):
    """The monotonic strength test of one assembled biaxial specimen at p."""
    out = writable_file(args.out)
    ds_in = open_netcdf(args.assembled, "assembled")
    if kind_of(ds_in) != "biaxial":
        raise ConfigError(args.assembled, None, "a strength test needs a biaxial specimen")
    cfg = load_config(args.config)
    st = cfg["strength"]
    recorder = Recorder("case strength", inputs=(args.assembled, args.config),
                        params={"confining_pressure_kPa": args.p_kPa, "strength": st, "case": args.case})
    rig = BiaxialRig.from_dataset(ds_in, "engine_checkpoint")
    rig.params = params_from_config("biaxial", cfg.get("rig", {}))     # as the scenario runner does
    bar = tqdm(desc="axial strain", total=round(st["axial_strain_max"], 4), unit="", disable=args.quiet,
               bar_format="{desc}: {n:.4f}/{total:.4f}")
    try:
        result = run_strength(rig, args.p_kPa, st["inertial_number"], st["axial_strain_max"],
                              st["side_servo_gain_m_s_per_kPa"], st["side_servo_integral_steps"],
                              progress=lambda ea: bar.update(max(0.0, round(ea, 4) - bar.n)))
    except RuntimeError as err:      # a consolidation that does not converge: say where, exit 2
        raise ConfigError(args.assembled, "rig", str(err)) from None
    finally:
        bar.close()
    ds = strength_dataset(result, args.p_kPa, {"case": args.case, "specimen": str(args.assembled)})
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp)
    recorder.finish()
    recorder.write_beside(out)
    if not args.quiet:
        print(f"wrote {out}: q_peak {result.q_peak / 1e3:.1f} kPa, phi_peak {result.phi_peak_deg:.1f} deg, "
              f"psi {result.dilatancy_angle_deg:.1f} deg at axial strain {result.axial_strain_at_peak:.4f}")


def _case_envelope(args):
    out = writable_file(args.out)
    recorder = Recorder("case envelope", inputs=args.tests)
    datasets = [open_netcdf(p, "strength") for p in args.tests]
    try:
        ds = strength_envelope(datasets)
    except ValueError as err:
        raise ConfigError(args.tests[0], None, str(err)) from None
    with atomic_path(out) as tmp:
        ds.to_netcdf(tmp)
    recorder.finish()
    recorder.write_beside(out)
    if not args.quiet:
        for k, p in enumerate(ds["confining_pressure"].values):
            print(f"p {p / 1e3:g} kPa: q_peak {float(ds['q_peak_mean'][k]) / 1e3:.1f} kPa, phi_peak "
                  f"{float(ds['phi_peak_deg_mean'][k]):.1f} +- {float(ds['phi_peak_deg_std'][k]):.1f} deg")


def register(subparsers):
    """Add the ``case`` stage (actions ``assemble`` and ``run``)."""
    c = subparsers.add_parser("case", help="cases of a rig: assembly and loading (thesis 4.2.2-4.2.3)")
    cs = c.add_subparsers(dest="action", required=True)

    a = cs.add_parser("assemble", help="drop, tamp and relax stones from a BPM library")
    a.add_argument("library", metavar="BPM.nc", type=Path, help="the stones' bonded-particle library (bpm build)")
    a.add_argument("--case", type=integer(0, 1_000_000), required=True, help="case number (selects the seed)")
    a.add_argument("--out", required=True, type=Path, help="assembled state (.nc)")
    a.add_argument("--seed", type=SEED, help="override the seed derived from (study seed, database, case)")
    a.add_argument("--rig", choices=("box", "biaxial"), help="override the config's rig.kind")
    a.add_argument("--width-m", dest="width_m", type=number(0.01, 100), help="biaxial: specimen width (config's)")
    a.add_argument("--height-m", dest="height_m", type=number(0.01, 100), help="biaxial: specimen height (config's)")
    a.add_argument("--membrane-segments", dest="membrane_segments", type=integer(1, 40),
                   help="biaxial: 1 rigid side walls, n > 1 a membrane of n segments a side (config's)")
    add_config(a)
    add_quiet(a)
    a.set_defaults(func=_case_assemble)


    r = cs.add_parser("run", help="static pre-loading, cyclic loading, metrics.nc")
    r.add_argument("assembled", metavar="ASSEMBLED.nc", type=Path, help="an assembled specimen (case assemble)")
    r.add_argument("--cycles", type=integer(1, 10_000_000), required=True, help="loading cycles (thesis 1000)")
    r.add_argument("--out", required=True, type=Path, help="metrics file (.nc)")
    r.add_argument("--checkpoint-every", type=integer(1, 10_000_000), help="cycles between checkpoints (config default)")
    r.add_argument("--restart", action="store_true", help="ignore an existing checkpoint")
    r.add_argument("--stop-after", type=integer(1, 10_000_000), help=argparse.SUPPRESS)
    r.add_argument("--no-vtk", action="store_true", help="write no VTK snapshots")
    r.add_argument("--no-figures", action="store_true", help="write no PNG figures")
    r.add_argument("--conditions", type=Path, help="run under this measured test's "
                   "conditions (its YAML; biaxial: p, q bounds and f; box: the load bounds)")
    r.add_argument("--mode", choices=("quasi_static", "real_time"), help="biaxial: override "
                   "the loading mode")
    r.add_argument("--parameters", type=Path, help="a calibrated.yaml (ballaststudy calibrate): "
                   "its parameters instead of Table 4.2's (a fresh run; a resumed one keeps its own)")
    r.add_argument("--strength-envelope", type=Path, help="the specimens' strength envelope "
                   "(case envelope), for the config's stress_mapping strength_ratio")
    r.add_argument("--stone-model", choices=tuple(STONE_MODELS), help="how the stones are "
                   "modelled in this run (default: the config's stone_model; ballaststudy.stones)")
    r.add_argument("--effect", action="append", metavar="NAME:PARAMETER=VALUE,...", help="add an "
                   "effect (scenario.modifiers) with its parameters, e.g. fatigue:fatigue_exponent=10,"
                   "endurance_ratio=0.3 (repeatable; give the same again to resume a run)")
    add_config(r)
    add_quiet(r)
    r.set_defaults(func=_case_run)

    t = cs.add_parser("strength", help="biaxial: monotonic compression through the peak at p")
    t.add_argument("assembled", metavar="ASSEMBLED.nc", type=Path, help="an assembled biaxial specimen (case assemble)")
    t.add_argument("--confining-pressure-kPa", dest="p_kPa", type=number(0.001, 1e6), required=True,
                   help="the confining pressure p held while the specimen is compressed [kPa]")
    t.add_argument("--case", type=integer(0, 1_000_000), default=0, help="the specimen's case number (recorded)")
    t.add_argument("--out", required=True, type=Path, help="strength test (.nc)")
    add_config(t)
    add_quiet(t)
    t.set_defaults(func=_case_strength)

    e = cs.add_parser("envelope", help="strength envelope of strength tests (case strength)")
    e.add_argument("tests", metavar="STRENGTH.nc", type=Path, nargs="+", help="strength tests (case strength) at several p")
    e.add_argument("--out", required=True, type=Path, help="envelope (.nc)")
    add_quiet(e)
    e.set_defaults(func=_case_envelope)
    return c
