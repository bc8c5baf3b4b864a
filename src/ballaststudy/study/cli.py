"""`ballaststudy study ...`: aggregate, iri, optimise, record, pack, merge, differences. `register(subparsers)` adds the stage to
the main parser (ballaststudy.cli). Bad input raises ConfigError (file, key, allowed range),
which the main command prints as one line with exit code 2; no partial outputs are left."""

from pathlib import Path

from ..config import ConfigError
from ..provenance import Recorder
from ..inputs import open_netcdf, writable_dir, writable_file
from .aggregate import BEHAVIOURS, aggregate, identify_metrics
from .differences import write_differences
from .iri import write_iri
from .parts import merge_parts, pack_part
from .record import write_record
from .report import write_report
from ..argtypes import SEED, integer, number


def _forms_name(path):
    ds = open_netcdf(path, "forms")
    return str(ds.attrs.get("database", Path(path).name.removesuffix(".nc")))


def _pairs(items, argument, form, once=False):
    """{key: value} from KEY=VALUE items in their order; ``once``: a key given twice is refused."""
    out = {}
    for item in items or ():
        key, sep, value = item.partition("=")
        if not sep or not key or not value:
            raise ConfigError("command line", argument, f"{item!r} is not {form}")
        if once and key in out:
            raise ConfigError("command line", argument, f"{key!r} given twice")
        out[key] = value
    return out


def _study_differences(args):
    writable_dir(args.out)
    command = " ".join(["ballaststudy study differences", *args.levels, "--out", str(args.out),
                        *([f"--at-cycle {args.at_cycle}"] if args.at_cycle is not None else []),
                        *(f"--confirm {c}" for c in args.confirm or ())])
    levels = {k: Path(v) for k, v in _pairs(args.levels, "LEVEL=PART", "LEVEL=PART", once=True).items()}
    confirm = {k: Path(v) for k, v in _pairs(args.confirm, "--confirm", "LEVEL=PART", once=True).items()}
    for path in write_differences(levels, args.out, command, args.resamples, args.seed,
                                  args.at_cycle, confirm):
        print(f"wrote {path}")


def _study_aggregate(args):
    writable_file(args.out)
    metrics = {}
    for p in args.metrics:
        key = identify_metrics(p)
        if key in metrics:
            raise ConfigError(p, None, f"database {key[0]} case {key[1]} also given by {metrics[key]}")
        metrics[key] = Path(p)
    forms = {}
    for p in args.forms:
        name = _forms_name(p)
        if name in forms:
            raise ConfigError(p, "database", f"{name} also given by {forms[name]}")
        forms[name] = Path(p)
    groups = _pairs(args.group, "--group", "DATABASE=GROUP")
    print(f"wrote {aggregate(metrics, forms, args.out, groups)}")


def _load_study(path):
    return open_netcdf(path, "study", require=tuple(BEHAVIOURS))


def _write_with_provenance(step, args, params, write):
    recorder = Recorder(step, inputs=[args.study], params=params, seed=args.seed)
    paths = write()
    recorder.finish()
    texts = [p for p in paths if p.suffix in (".csv", ".md")]
    for k, path in enumerate(texts):    # the figures go in the first text's record
        recorder.write_beside(path, also=[] if k else [p for p in paths if p not in texts])
    for path in paths:
        print(f"wrote {path}")


def _study_iri(args):
    writable_dir(args.out)
    study = _load_study(args.study)
    _write_with_provenance("study iri", args, {"resamples": args.resamples, "min_rho": args.min_rho},
                           lambda: write_iri(study, args.out, args.resamples, args.seed, args.min_rho))


def _study_optimise(args):
    writable_dir(args.out)
    study = _load_study(args.study)
    _write_with_provenance("study optimise", args, {"resamples": args.resamples},
                           lambda: write_report(study, args.out, args.resamples, args.seed, str(args.study)))


def _study_record(args):
    writable_dir(args.out)
    command = " ".join(["ballaststudy study record", str(args.results), "--out", str(args.out),
                        *[f"--time-log {p}" for p in args.time_log or ()]])
    for path in write_record(args.results, args.out, args.time_log or (), command):
        print(f"wrote {path}")


def _study_pack(args):
    writable_dir(args.out)
    command = " ".join(["ballaststudy study pack", str(args.results), "--out", str(args.out),
                        *[f"--time-log {p}" for p in args.time_log or ()]])
    for path in pack_part(args.results, args.out, args.time_log or (), command):
        print(f"wrote {path}")


def _study_merge(args):
    writable_dir(args.out)
    for path in merge_parts(args.parts, args.out):
        print(f"wrote {path}")


def _analysis_parser(actions, name, help_text):
    """An action reading STUDY.nc into an output folder with seeded bootstrap intervals."""
    p = actions.add_parser(name, help=help_text)
    p.add_argument("study", type=Path, metavar="STUDY.nc", help="the aggregated study (study aggregate)")
    p.add_argument("--out", required=True, type=Path, help="output folder")
    p.add_argument("--resamples", type=integer(100, 100_000), default=2000, help="bootstrap resamples (>= 100)")
    p.add_argument("--seed", type=SEED, default=0, help="bootstrap seed")
    return p


def register(subparsers):
    """Add the `study` stage (actions aggregate, iri, optimise) to `subparsers`."""
    st = subparsers.add_parser("study", help="aggregate metrics to study.nc, IRI tables, optimisation (thesis ch. 5)")
    ss = st.add_subparsers(dest="action", required=True)

    a = ss.add_parser("aggregate", help="per-case metrics.nc + form databases -> study.nc")
    a.add_argument("metrics", nargs="+", metavar="METRICS.nc",
                   help="per (database, case): attributes 'database'/'case' or path .../<database>/<case>/metrics.nc")
    a.add_argument("--forms", nargs="+", required=True, metavar="FORMS.nc",
                   help="form databases (results/forms/<db>.nc)")
    a.add_argument("--out", required=True, type=Path, help="output file, e.g. results/study.nc")
    a.add_argument("--group", action="append", metavar="DATABASE=GROUP",
                   help="override a database's group (default: forms attribute 'group', else G_<group>-<i>)")
    a.set_defaults(func=_study_aggregate)

    i = _analysis_parser(ss, "iri", "IRI tables like thesis Table 5-2: CSV, Markdown, heatmap")
    i.add_argument("--min-rho", type=number(0.0, 1.0), default=0.3, help="smallest absolute Spearman rho for a verdict other than none")
    i.set_defaults(func=_study_iri)

    o = _analysis_parser(ss, "optimise", "ranking, Pareto set, recommendation, thesis findings, Figs. 5-1 ... 5-6")
    o.set_defaults(func=_study_optimise)

    r = ss.add_parser("record", help="a study's reference record beside thesis ch. 5 (e.g. docs/thesis-scale/)")
    r.add_argument("results", type=Path, metavar="RESULTS", help="the run's results folder (study.nc, study/, records)")
    r.add_argument("--out", required=True, type=Path, help="output folder, e.g. docs/thesis-scale")
    r.add_argument("--time-log", action="append", type=Path, metavar="LOG",
                   help="a /usr/bin/time -v log of a snakemake command that made the run (repeat for parts)")
    r.set_defaults(func=_study_record)

    k = ss.add_parser("pack", help="keep a part's study (study.nc, records, time logs) in a folder, e.g. to commit it")
    k.add_argument("results", type=Path, metavar="RESULTS", help="the part's results folder (its study.nc made)")
    k.add_argument("--out", required=True, type=Path, help="the part's folder, e.g. docs/thesis-scale/parts/group_3")
    k.add_argument("--time-log", action="append", type=Path, metavar="LOG",
                   help="a /usr/bin/time -v log of a snakemake command of the part (repeat)")
    k.set_defaults(func=_study_pack)

    m = ss.add_parser("merge", help="parts (study pack) -> one results folder: study.nc and the records")
    m.add_argument("parts", nargs="+", type=Path, metavar="PART", help="part folders written by study pack")
    m.add_argument("--out", required=True, type=Path, help="results folder for the iri, optimise and record stages")
    m.set_defaults(func=_study_merge)

    d = ss.add_parser("differences", help="the screening of the thesis' headline contrasts, one study part per "
                                          "level (docs/thesis-scale/differences.md)")
    d.add_argument("levels", nargs="+", metavar="LEVEL=PART",
                   help="a level's name and its part folder (study pack), e.g. ours=docs/thesis-scale/differences/ours")
    d.add_argument("--out", required=True, type=Path, help="output folder, e.g. docs/thesis-scale")
    d.add_argument("--resamples", type=integer(100, 100_000), default=2000, help="bootstrap resamples (>= 100)")
    d.add_argument("--seed", type=SEED, default=0, help="bootstrap seed")
    d.add_argument("--at-cycle", type=integer(0, 10**9), default=None,
                   help="read every case at this cycle where it ran longer (default: its last), e.g. 299 to read "
                        "the 1000-cycle thesis-scale study beside the 300-cycle screening")
    d.add_argument("--confirm", action="append", metavar="LEVEL=PART",
                   help="a confirmation's level and part (config/differences/confirm_<level>.yaml, merged parts), "
                        "read at its last cycle; repeat for each")
    d.set_defaults(func=_study_differences)
    return st
