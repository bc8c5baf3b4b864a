"""`ballaststudy case ...`: assemble a case of the configured rig (``rig.kind``: the box
test or the cyclic biaxial test; ``--rig`` overrides) from a BPM library and load it.

    ballaststudy case assemble BPM.nc --case K --out results/cases/DB/caseK/assembled.nc
    ballaststudy case run ASSEMBLED.nc --cycles N --out results/cases/DB/caseK/metrics.nc

``register(subparsers)`` adds the ``case`` stage to the main parser (wired in cli.py).
"""
import json
import sys
import time
from pathlib import Path

from tqdm import tqdm

from ..config import ConfigError, load_config
from ..inputs import open_netcdf, writable_dir, writable_file
from ..provenance import Recorder
from .kinds import RUNS_TESTS, kind_of, params_from_config, rig_classes
from .params import case_seed
from ..argtypes import SEED, integer, number


def _kind(args, cfg):
    return getattr(args, "rig", None) or cfg["rig"].get("kind", "box")


def _params(args, kind=None):
    cfg = load_config(args.config)
    return cfg, params_from_config(kind or _kind(args, cfg), cfg.get("rig", {}))


def _case_assemble(args):
    from .assembly import assemble
    from .biaxial import assemble_biaxial
    from .library import load_library
    writable_file(args.out)
    cfg, params = _params(args)
    biaxial = _kind(args, cfg) == "biaxial"
    assemble = assemble_biaxial if biaxial else assemble
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
    rig = assemble(lib, params, seed, progress=bar.update)
    bar.close()
    rig.save(args.out, attrs={"case": args.case, "library_file": str(args.library),
                              "assembly_seconds": round(time.time() - t0, 1)})
    recorder.finish()
    recorder.write_beside(args.out)
    lay = rig.layout
    if not args.quiet:
        print(f"wrote {args.out}: {len(lay.stone_library_index)} stones, "
              f"{rig.stone_balls().size} balls, {lay.bonds_installed} bonds, "
              f"steps {lay.stage_steps}")


def _measured_conditions(args, kind, params):
    """A run under a measured test's conditions (biaxial: p, q bounds, f; box: the load
    bounds) and/or a biaxial mode."""
    if args.mode:
        if kind != "biaxial":
            raise ConfigError(args.assembled, None, "--mode needs a biaxial case")
        params.mode = args.mode
    if args.conditions:
        from ..measured.importer import load_conditions
        c = load_conditions(args.conditions)
        if c["rig"] not in RUNS_TESTS[kind]:
            raise ConfigError(args.conditions, "rig", f"{c['rig']}: a {kind} case runs "
                              f"{' or '.join(RUNS_TESTS[kind])} conditions")
        try:
            params.take_conditions(c)
        except ValueError as err:     # a bound of the test against the config's other bound
            raise ConfigError(args.conditions, None, str(err)) from None


def _case_run(args):
    out = writable_file(args.out)
    ckpt = writable_file(out.with_name(out.stem + ".checkpoint.npz"))
    assembled = open_netcdf(args.assembled, "assembled")
    kind = kind_of(assembled)
    rig_class, run_class, write_outputs = rig_classes(kind)
    cfg, params = _params(args, kind)
    if args.conditions or args.mode:
        _measured_conditions(args, kind, params)
    material = {}
    if args.parameters:
        from ..calibration.parameters import load_calibrated
        material = load_calibrated(args.parameters)
    recorder = Recorder("case run", inputs=(args.assembled, args.config,
                                            *[p for p in (args.conditions, args.parameters) if p]),
                        params={"cycles": args.cycles, "rig": params.to_dict(),
                                "metrics": cfg.get("metrics"), "material_parameters": material})
    if ckpt.exists() and not args.restart:
        run = run_class.from_checkpoint(ckpt, cycles=args.cycles,
                                        checkpoint_every=args.checkpoint_every)
        if not args.quiet:
            print(f"resuming from {ckpt} (cycle {run.s.cycle}, step {run.rig.sim.step})")
    else:
        try:
            rig = rig_class.from_dataset(assembled, "engine_checkpoint")
        except (ValueError, KeyError, TypeError) as err:
            raise ConfigError(args.assembled, None, f"not an assembled case ({err})") from None
        rig.params = params
        if material:                    # calibrated values instead of Table 4.2's
            from ..calibration.parameters import apply_parameters
            apply_parameters(rig, material)
        run = run_class(rig, args.cycles, checkpoint=ckpt,
                        checkpoint_every=args.checkpoint_every, metrics=cfg.get("metrics"))
    vtk_dir = None if args.no_vtk else writable_dir(out.with_name("vtk"))
    if vtk_dir is not None:
        from .vtk import vtk_hook
        run.hooks.append(vtk_hook(vtk_dir, params.vtk_cycles, args.cycles))
    bar = tqdm(total=args.cycles, initial=run.s.cycle, desc="cycles", unit="cycle",
               disable=args.quiet)
    last = [run.s.cycle, None]

    def progress(phase, cycle):
        if cycle != last[0]:
            bar.update(cycle - last[0])
            last[0] = cycle
        if phase != last[1]:
            last[1] = phase
            bar.set_postfix_str(phase)

    try:
        run.run(progress=progress, stop_after=args.stop_after)
    except RuntimeError as err:      # a stage that does not converge: say where, exit 2
        kept = f" (checkpoint kept: {ckpt})" if ckpt.exists() else ""
        raise ConfigError(args.assembled, "rig", f"{err}{kept}") from None
    finally:
        bar.close()
    if run.s.phase != "done":
        print(f"stopped after cycle {run.s.cycle} (checkpoint {ckpt})", file=sys.stderr)
        return
    attrs = {"assembled_file": str(args.assembled)}
    if args.conditions:
        attrs["measured_conditions_file"] = str(args.conditions)
    attrs["material_parameters"] = f"calibrated ({args.parameters})" if material else "table_4_2"
    attrs["material_parameters_json"] = json.dumps(material)       # {} for Table 4.2's
    write_outputs(run, out, figures=not args.no_figures, attrs=attrs)
    if getattr(run.s, "failure", ""):     # a result (recorded in the file), not an error
        print(f"ballaststudy: note: {out}: {run.s.failure} (after {run.s.cycle} cycles)", file=sys.stderr)
    recorder.finish()
    figures = [] if args.no_figures else [out.with_name("case.png"), out.with_name("behaviours.png")]
    vtk = sorted(p for p in vtk_dir.rglob("*") if p.is_file()) if vtk_dir is not None else []
    kept = [p for p in (*figures, ckpt) if p.is_file()]     # the checkpoint: to extend the run later
    recorder.write_beside(out, also=kept + vtk)
    if not args.quiet:
        print(f"wrote {out}")


def register(subparsers):
    """Add the ``case`` stage (actions ``assemble`` and ``run``)."""
    c = subparsers.add_parser("case", help="box-test cases: assembly and loading (thesis 4.2.2-4.2.3)")
    cs = c.add_subparsers(dest="action", required=True)

    a = cs.add_parser("assemble", help="drop, tamp and relax stones from a BPM library")
    a.add_argument("library", metavar="BPM.nc", type=Path)
    a.add_argument("--case", type=integer(0, 1_000_000), required=True, help="case number (selects the seed)")
    a.add_argument("--out", required=True, type=Path, help="assembled state (.nc)")
    a.add_argument("--seed", type=SEED, help="override the seed derived from (study seed, database, case)")
    a.add_argument("--rig", choices=("box", "biaxial"), help="override the config's rig.kind")
    a.add_argument("--width-m", dest="width_m", type=number(0.01, 100), help="biaxial: specimen width (config's)")
    a.add_argument("--height-m", dest="height_m", type=number(0.01, 100), help="biaxial: specimen height (config's)")
    a.add_argument("--membrane-segments", dest="membrane_segments", type=integer(1, 40),
                   help="biaxial: 1 rigid side walls, n > 1 a membrane of n segments a side (config's)")
    a.add_argument("--config", default="config/config.yaml", type=Path)
    a.add_argument("--quiet", action="store_true")
    a.set_defaults(func=_case_assemble)

    r = cs.add_parser("run", help="static pre-loading, cyclic loading, metrics.nc")
    r.add_argument("assembled", metavar="ASSEMBLED.nc", type=Path)
    r.add_argument("--cycles", type=integer(1, 10_000_000), required=True, help="loading cycles (thesis 1000)")
    r.add_argument("--out", required=True, type=Path, help="metrics file (.nc)")
    r.add_argument("--checkpoint-every", type=integer(1, 10_000_000), help="cycles between checkpoints (config default)")
    r.add_argument("--restart", action="store_true", help="ignore an existing checkpoint")
    r.add_argument("--stop-after", type=integer(1, 10_000_000), help=argparse_suppress())
    r.add_argument("--no-vtk", action="store_true", help="write no VTK snapshots")
    r.add_argument("--no-figures", action="store_true", help="write no PNG figures")
    r.add_argument("--conditions", type=Path, help="run under this measured test's "
                   "conditions (its YAML; biaxial: p, q bounds and f; box: the load bounds)")
    r.add_argument("--mode", choices=("quasi_static", "real_time"), help="biaxial: override "
                   "the loading mode")
    r.add_argument("--parameters", type=Path, help="a calibrated.yaml (ballaststudy calibrate): "
                   "its parameters instead of Table 4.2's (a fresh run; a resumed one keeps its own)")
    r.add_argument("--config", default="config/config.yaml", type=Path)
    r.add_argument("--quiet", action="store_true")
    r.set_defaults(func=_case_run)
    return c


def argparse_suppress():
    import argparse
    return argparse.SUPPRESS
