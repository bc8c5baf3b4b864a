"""`ballaststudy measured fetch`: the public curves from their source; `ballaststudy measured
import`: one measured cyclic test (conditions YAML + curve files) to one netCDF. Bad input
raises ConfigError (file[:line], key, what is allowed), printed as one line with exit code
2; nothing is written then."""
from pathlib import Path

import pooch

from ..argtypes import add_quiet
from ..inputs import input_dir, input_file, writable_file
from ..provenance import Recorder
from .compare import write_comparison
from .fetch import SOURCE_COMMIT, SOURCE_REPOSITORY, SOURCE_URL, fetch
from .importer import curve_files, measured_dataset, write_test


def _import(args):
    writable_file(args.out)
    if args.data_dir:
        input_dir(args.data_dir, "expected the folder of the curve files")
    ds = measured_dataset(args.conditions, args.data_dir)     # every check before any output
    recorder = Recorder("measured import",
                        inputs=[args.conditions, *curve_files(args.conditions, args.data_dir)],
                        params={"data_dir": str(args.data_dir) if args.data_dir else None})
    write_test(ds, args.out)
    recorder.finish()
    recorder.write_beside(args.out)
    if not args.quiet:
        print(f"wrote {args.out}: {', '.join(ds.data_vars)} at {ds.sizes['cycle']} cycles")


def _fetch(args):
    pooch.get_logger().setLevel("WARNING" if args.quiet else "INFO")
    paths = fetch(args.data_dir, args.url)
    if not args.quiet:
        print(f"{len(paths)} curve files in {args.data_dir}, checked against their SHA-256")


def _compare(args):
    out = writable_file(args.out)
    figure = None if args.no_figure else writable_file(out.with_suffix(".png"))
    inputs = [input_file(p, "expected a netCDF file") for p in (args.measured, *args.cases)]
    recorder = Recorder("measured compare", inputs=inputs)    # hashes them: they must exist
    ds = write_comparison(args.measured, args.cases, out, figure=figure)
    recorder.finish()
    recorder.write_beside(out, also=[figure] if figure else [])
    if not args.quiet:
        print(f"wrote {args.out}: {ds.sizes['case']} simulated cases on {ds.sizes['cycle']} cycles")


def register(subparsers):
    """Add the ``measured`` stage."""
    m = subparsers.add_parser("measured", help="measured cyclic tests in (curves + conditions)")
    ms = m.add_subparsers(dest="action", required=True)
    f = ms.add_parser("fetch", help="the public measured curves from their source, each checked by its hash")
    f.add_argument("--data-dir", required=True, type=Path, help="folder to put them in (measured.data_dir)")
    f.add_argument("--url", default=SOURCE_URL,
                   help=f"where the source's experimental_data/ folder is (default: {SOURCE_REPOSITORY} "
                        f"at commit {SOURCE_COMMIT[:7]}; a mirror of it)")
    add_quiet(f)
    f.set_defaults(func=_fetch)
    i = ms.add_parser("import", help="one test's curves and conditions -> netCDF")
    i.add_argument("conditions", metavar="TEST.yaml", type=Path,
                   help="the test's conditions and curve files (schemas/measured.schema.yaml)")
    i.add_argument("--out", required=True, type=Path, help="netCDF to write")
    i.add_argument("--data-dir", type=Path,
                   help="folder to look up curve files not found beside the YAML")
    add_quiet(i)
    i.set_defaults(func=_import)
    c = ms.add_parser("compare", help="a measured test beside its simulated cases -> netCDF + PNG")
    c.add_argument("measured", type=Path, help="the test's netCDF (measured import)")
    c.add_argument("cases", nargs="+", type=Path, help="metrics.nc of its biaxial cases")
    c.add_argument("--out", required=True, type=Path, help="the comparison's netCDF (its figure beside it, .png)")
    c.add_argument("--no-figure", action="store_true", help="write no figure")
    add_quiet(c)
    c.set_defaults(func=_compare)
    return m
