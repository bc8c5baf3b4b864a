"""The `ballaststudy` command: one subcommand per stage of the chain."""

import argparse
import functools
import json
import sys
from pathlib import Path

import pandas as pd
from tqdm import tqdm

from .atomic import atomic_path
from .config import (ConfigError, database_seed, form_params, load_config, load_databases,
                     select_databases, unknown_set_databases)
from .forms.evaluate import MeshError, evaluate_stl, units_warning
from .forms.generator import GenerationError
from .forms.objective import ObjectiveError
from .forms.pipeline import generate_database
from .forms.report import write_report
from .forms.validate import SUMMARY_COLUMNS, validation_row
from .inputs import input_dir, input_file, open_netcdf, writable_dir, writable_file
from .provenance import Recorder
from .provenance.store import lineage, load_records, verify, write_store
from .bpm.cli import register as register_bpm
from .calibration.cli import check_targets, register as register_calibrate
from .cluster.spec import executor_spec
from .loop.cli import register as register_loop
from .loop.horizon_cli import register as register_horizon
from .measured.cli import register as register_measured
from .measured.importer import load_conditions
from .scenario.cli import register as register_case
from .study.cli import register as register_study
from .argtypes import SEED, add_config, add_quiet, integer


def _forms_generate(args):
    writable_dir(args.out)
    cfg = load_config(args.config)
    params = form_params(cfg)
    databases = load_databases(cfg["databases_file"], params)
    if args.all == bool(args.names):
        raise ConfigError("command line", "DATABASE", "name databases or give --all (not both)")
    names = select_databases(cfg if args.all else {"databases": args.names}, databases, args.config)
    bar = tqdm(names, desc="form databases", unit="db", disable=args.quiet)
    for name in bar:
        bar.set_postfix_str(name)
        definition = databases[name]
        nc = generate_database(name, definition, database_seed(cfg["seed"], name, definition), params,
                               args.out, config_files=(args.config, cfg["databases_file"]))
        if not args.quiet:
            tqdm.write(f"wrote {nc}")


def _forms_validate(args):
    if args.csv:
        writable_file(args.csv)
    rows = [validation_row(open_netcdf(p, "forms")) for p in args.files]
    if args.csv:
        with atomic_path(args.csv) as tmp:
            pd.DataFrame(rows).to_csv(tmp, index=False)
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        table = pd.DataFrame(rows)[SUMMARY_COLUMNS]
        with pd.option_context("display.width", 250, "display.max_columns", 40):
            print(table.to_string(index=False, float_format=lambda v: f"{v:.3f}"))


def _forms_evaluate(args):
    result = evaluate_stl(args.stl, args.density, args.units)
    warning = units_warning(args.stl, result)
    if warning:     # a wrong --units still gives numbers (off by 1000): warn, do not fail
        print(f"ballaststudy: warning: {warning}", file=sys.stderr)
    print(json.dumps(result, indent=1))


def _forms_report(args):
    writable_dir(args.out)
    databases = [open_netcdf(p, "forms") for p in args.files]
    recorder = Recorder("forms report", inputs=args.files, params={"stones": args.stones, "seed": args.seed})
    paths = write_report(databases, args.out, args.stones, args.seed)
    recorder.finish()
    tables = [p for p in paths if str(p).endswith(".csv")]
    for k, path in enumerate(tables):   # the figures go in the first table's record
        recorder.write_beside(path, also=[] if k else [p for p in paths if p not in tables])
    for path in paths:
        print(f"wrote {path}")


def _provenance_show(args):
    records = load_records(input_dir(args.results, "expected the results folder"))
    if str(Path(args.file)) not in records:     # an output with a record may be gone: still show it
        input_file(args.file, f"expected an output file or one recorded under {args.results}")
    print("\n".join(lineage(args.file, records)))


def _provenance_verify(args):
    records = load_records(input_dir(args.results, "expected the results folder"))
    store = writable_file(Path(args.results) / "provenance" / "store.json")
    write_store(args.results, store)
    problems = verify(records)
    for path, what in problems:
        print(f"{path}: {what}")
    print(f"{len({id(r) for r in records.values()})} records, {len(problems)} problems")
    if problems:
        raise SystemExit(1)


def _config_check(args):
    """What the workflow reads before any job: the config, its databases, the measured tests."""
    cfg = load_config(args.config)
    dbs = load_databases(cfg["databases_file"], form_params(cfg))
    names = select_databases(cfg, dbs, args.config)
    for note in unknown_set_databases(cfg, dbs):
        print(note, file=sys.stderr)
    tests_dir = Path(cfg["measured"]["tests_dir"])
    tests = sorted(tests_dir.rglob("*.yaml"))
    for test in tests:
        load_conditions(test)
    check_targets(cfg, args.config, [str(t.relative_to(tests_dir).with_suffix("")) for t in tests])
    executor_spec(cfg, args.config, submit=False)
    print(f"{args.config}: ok ({len(names)} databases: {', '.join(names)}; {len(tests)} measured tests)")


class OneLineParser(argparse.ArgumentParser):
    """argparse with a usage error in one line like every other bad input (exit 2)."""

    def error(self, message):
        self.exit(2, f"ballaststudy: error: {self.prog}: {message} (see {self.prog} --help)\n")


@functools.lru_cache(maxsize=1)
def build_parser():
    """The command line's parser, built once per process: a build took ~36 ms (argparse
    looks up its message translations for every one of ~30 subparsers), half of a `config
    check` called in process (the fuzz suite calls main 2300 times); parsing leaves it
    unchanged."""
    p = OneLineParser(prog="ballaststudy", description=__doc__)
    sub = p.add_subparsers(dest="stage", required=True)

    forms = sub.add_parser("forms", help="ballast random form generator (thesis ch. 3)")
    fs = forms.add_subparsers(dest="action", required=True)
    g = fs.add_parser("generate", help="generate form databases")
    g.add_argument("names", nargs="*", metavar="DATABASE", help="databases to generate (names in config/databases.yaml)")
    g.add_argument("--all", action="store_true", help="every database the config selects")
    g.add_argument("--out", required=True, type=Path, help="output folder")
    add_config(g)
    add_quiet(g)
    g.set_defaults(func=_forms_generate)

    v = fs.add_parser("validate", help="objective vs generated parameters")
    v.add_argument("files", nargs="+", metavar="FILE.nc", help="form databases (forms generate)")
    v.add_argument("--json", action="store_true", help="print a JSON list, one object per database")
    v.add_argument("--csv", type=Path, help="also write the full table as CSV")
    v.set_defaults(func=_forms_validate)

    e = fs.add_parser("evaluate", help="a, b, c, volume, group and flags of one STL stone")
    e.add_argument("stl", metavar="STONE.stl", help="a closed triangle mesh of one stone")
    # --density and --units are checked by evaluate_stl, for a one-line error like every other
    e.add_argument("--density", metavar="KG_M3", help="give the mass too (kg/m3, finite and > 0)")
    e.add_argument("--units", default="mm", metavar="mm|m",
                   help="unit of the file's coordinates and of the output keys (default mm, as scans and EN 933)")
    e.set_defaults(func=_forms_evaluate)

    r = fs.add_parser("report", help="figures like thesis Figs. 3-9 ... 3-16")
    r.add_argument("files", nargs="+", metavar="FILE.nc", help="form databases (forms generate)")
    r.add_argument("--out", required=True, type=Path, help="folder for the report's figures and tables")
    r.add_argument("--stones", type=integer(1, 25), default=9, help="random stones per database (Fig. 3-9)")
    r.add_argument("--seed", type=SEED, default=0, help="which random stones are shown")
    r.set_defaults(func=_forms_report)

    pv = sub.add_parser("provenance", help="what made an output, and is it still current")
    ps = pv.add_subparsers(dest="action", required=True)
    sh = ps.add_parser("show", help="lineage of one output back to the config")
    sh.add_argument("file", help="an output file of the workflow")
    sh.add_argument("--results", default="results", help="the results folder whose provenance/ holds the records")
    sh.set_defaults(func=_provenance_show)
    vf = ps.add_parser("verify", help="re-hash every recorded input and output; exit 1 if any changed")
    vf.add_argument("--results", default="results", help="the results folder whose provenance/ holds the records")
    vf.set_defaults(func=_provenance_verify)

    register_bpm(sub)
    register_case(sub)
    register_study(sub)
    register_measured(sub)
    register_calibrate(sub)
    register_loop(sub)
    register_horizon(sub)

    c = sub.add_parser("config", help="configuration")
    cs = c.add_subparsers(dest="action", required=True)
    ck = cs.add_parser("check", help="validate the config and database definitions")
    add_config(ck)
    ck.set_defaults(func=_config_check)
    return p


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        args.func(args)
    except (ConfigError, ObjectiveError, GenerationError, MeshError) as err:
        print("ballaststudy: error: " + " ".join(str(err).splitlines()), file=sys.stderr)  # one line
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
