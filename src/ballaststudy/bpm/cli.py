"""``ballaststudy bpm build FORMS.nc --out BPM.nc``: the CLI stage (registered by cli.py)."""

import sys
from pathlib import Path

from tqdm import tqdm

from ..config import ConfigError, job_seed, load_config
from ..inputs import writable_file
from ..argtypes import SEED, add_config, add_quiet, integer
from .library import build_library, open_forms
from .params import BpmParams


def bpm_seed(study_seed, database):
    """The library's seed: from the study seed and the database name (CRC-32, like every
    job seed), with a stage suffix so that it differs from the forms job's seed."""
    return job_seed(study_seed, f"{database}/bpm")


def _bpm_build(args):
    writable_file(args.out)
    cfg = load_config(args.config)
    try:
        params = BpmParams.from_config(cfg.get("bpm"))
    except (TypeError, ValueError) as err:
        raise ConfigError(args.config, "bpm", str(err)) from None
    if args.max_stones is not None:
        params = type(params)(**{**params.as_dict(), "max_stones": args.max_stones or None})
    forms = open_forms(args.forms)
    database = forms.attrs.get("database") or Path(args.forms).stem
    seed = bpm_seed(cfg["seed"], database) if args.seed is None else args.seed
    n = forms.sizes["stone"] if params.max_stones is None else min(params.max_stones,
                                                                    forms.sizes["stone"])
    with tqdm(total=n, desc=f"bpm {database}", unit="stone", disable=args.quiet) as bar:
        ds = build_library(args.forms, args.out, params, seed, config_files=(args.config,),
                           progress=bar.update)
    if ds.attrs["stones_not_converged"]:
        print(f"ballaststudy: warning: {ds.attrs['stones_not_converged']} stones stopped at "
              f"max_relax_cycles above the force ratio limit (see force_ratio in {args.out})",
              file=sys.stderr)
    if not args.quiet:
        print(f"wrote {args.out}: {ds.sizes['stone']} stones, {ds.sizes['ball']} balls, "
              f"{ds.sizes['bond']} bonds, force ratio max {ds.attrs['force_ratio_max']:.2g}")


def register(subparsers):
    """Add the ``bpm`` stage (action ``build``) to the top-level subparsers."""
    bpm = subparsers.add_parser("bpm", help="bonded particle models of the 2D forms (thesis 4.2.1)")
    bs = bpm.add_subparsers(dest="action", required=True)
    b = bs.add_parser("build", help="build the BPM library of one form database")
    b.add_argument("forms", type=Path, metavar="FORMS.nc", help="a form database (forms generate)")
    b.add_argument("--out", required=True, type=Path, metavar="BPM.nc", help="the bonded-particle library to write")
    add_config(b)
    b.add_argument("--max-stones", type=integer(1, 10_000_000), metavar="N",
                   help="override bpm.max_stones (0 = every stone)")
    b.add_argument("--seed", type=SEED, help="override the seed derived from the study seed")
    add_quiet(b)
    b.set_defaults(func=_bpm_build)
    return bpm
