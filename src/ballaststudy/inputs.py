"""Files and folders checked before any work: a bad one raises ConfigError, which
`ballaststudy` prints as one line `file: what is wrong; what was expected` (exit code 2).

A netCDF input's kind is recognised by what its writer always stores (variables,
dimensions, global attributes), so that the file of another stage is refused by name
instead of failing deep inside a reader. Each file is opened once and returned loaded."""

import os
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from .schema import ConfigError

_NETCDF_MAGIC = (b"CDF\x01", b"CDF\x02", b"\x89HDF\r\n\x1a\n")
_ZIP_MAGIC = b"PK\x03\x04"


@dataclass(frozen=True)
class Kind:
    """A kind of input file: what it is called, the command that writes it, what identifies it."""
    what: str
    maker: str
    variables: tuple = ()
    dims: tuple = ()
    attrs: tuple = ()
    hint: str = ""

    @property
    def expected(self):
        return f"expected {self.what} (from '{self.maker}'){self.hint}"

    def lacks(self, variables, dims=(), attrs=()):
        """The first identifying item missing ("variable 'a'"), or None."""
        for label, have, need in (("variable", variables, self.variables),
                                  ("dimension", dims, self.dims), ("attribute", attrs, self.attrs)):
            for name in need:
                if name not in have:
                    return f"{label} {name!r}"
        return None


# most specific first: a file refused as one kind is named by the first other kind it matches
KINDS = {
    "assembled": Kind("an assembled case", "ballaststudy case assemble", ("engine_checkpoint",),
                      attrs=("rig_layout_json", "rig_params_json")),
    "bpm": Kind("a BPM library", "ballaststudy bpm build",
                ("ball_count", "bond_count", "ball_x", "ball_y", "ball_radius", "bond_i", "bond_j")),
    "study": Kind("a study.nc", "ballaststudy study aggregate", dims=("database", "case", "cycle")),
    "measured": Kind("a measured test", "ballaststudy measured import", dims=("cycle",),
                     attrs=("conditions_file",)),
    "horizon": Kind("a long-term horizon table", "ballaststudy horizon",
                    ("median_abs_error", "stated_abs_error", "chosen_law"), dims=("law", "fit_cycles")),
    "forms": Kind("a form database", "ballaststudy forms generate", ("a", "b", "c", "mass")),
    "envelope": Kind("a strength envelope", "ballaststudy case envelope", ("q_peak_mean", "peak_reached"),
                     dims=("confining_pressure", "case")),
    "metrics": Kind("a case's metrics.nc", "ballaststudy case run", dims=("cycle",)),
    "strength": Kind("a strength test", "ballaststudy case strength", ("deviator_stress", "axial_strain"),
                     attrs=("q_peak", "confining_pressure_Pa", "case")),
}
CHECKPOINT = Kind("a checkpoint", "ballaststudy case run", ("engine", "state", "layout", "params", "cycles"),
                  hint="; run again with --restart to start afresh")


def input_file(path, expected):
    """`path` if it is a readable file; ConfigError otherwise."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(path, None, f"is a folder; {expected}")
    if not path.is_file():
        raise ConfigError(path, None, f"file not found; {expected}")
    if not os.access(path, os.R_OK):
        raise ConfigError(path, None, f"no permission to read it; {expected}")
    return path


def input_dir(path, expected):
    """`path` if it is a folder; ConfigError otherwise."""
    path = Path(path)
    if not path.exists():
        raise ConfigError(path, None, f"folder not found; {expected}")
    if not path.is_dir():
        raise ConfigError(path, None, f"is a file, not a folder; {expected}")
    return path


def _head(path):
    with open(path, "rb") as f:
        return f.read(8)


def _load(path, kind):
    """The Dataset, loaded and closed; a ConfigError that tells garbage from a damaged file."""
    head = _head(path)
    try:
        with xr.open_dataset(path) as ds:
            return ds.load()
    except (OSError, ValueError, RuntimeError) as err:
        if not head:
            problem = "empty file"
        elif head.startswith(_NETCDF_MAGIC):
            problem = f"damaged or truncated netCDF file ({getattr(err, 'strerror', None) or type(err).__name__})"
        else:
            problem = "not a netCDF file"
        raise ConfigError(path, None, f"{problem}; {kind.expected}") from None


def _identify(ds, skip):
    return next((k for name, k in KINDS.items() if name != skip
                 and k.lacks(ds.variables, ds.dims, ds.attrs) is None), None)


def open_netcdf(path, kind, require=()):
    """The netCDF file at `path` as a loaded Dataset, checked to be of `kind` (a key of
    KINDS) and to hold the variables `require` (what this reader needs beyond the kind)."""
    k = KINDS[kind]
    path = input_file(path, k.expected)
    ds = _load(path, k)
    need = Kind(k.what, k.maker, tuple(dict.fromkeys((*require, *k.variables))), k.dims, k.attrs)
    lacks = need.lacks(ds.variables, ds.dims, ds.attrs)
    if lacks:
        other = _identify(ds, kind)
        it_is = f" (it is {other.what})" if other else ""
        raise ConfigError(path, None, f"not {k.what}: no {lacks}{it_is}; {k.expected}")
    return ds


def open_checkpoint(path):
    """The arrays of a run checkpoint (npz) as a dict; ConfigError if it is not a usable one."""
    path = input_file(path, CHECKPOINT.expected)
    head = _head(path)
    if not head.startswith(_ZIP_MAGIC):
        problem = "empty file" if not head else "not a checkpoint file (npz)"
        raise ConfigError(path, None, f"{problem}; {CHECKPOINT.expected}")
    try:
        with np.load(path, allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as err:
        raise ConfigError(path, None, f"damaged or truncated checkpoint ({type(err).__name__}); "
                          f"{CHECKPOINT.expected}") from None
    lacks = CHECKPOINT.lacks(d)
    if lacks:
        raise ConfigError(path, None, f"not {CHECKPOINT.what}: no {lacks}; {CHECKPOINT.expected}")
    return d


def _check_creatable(path, folder):
    """The nearest existing folder at or above `folder` must be a folder we may write in."""
    probe = Path(os.path.abspath(folder))
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise ConfigError(path, None, f"cannot write here: {probe} is a file, not a folder; "
                          "expected a path in a writable folder")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ConfigError(path, None, f"cannot write here: no permission to write in {probe}; "
                          "expected a path in a writable folder")


def writable_file(path):
    """`path` if an output file can be written there (nothing is created); ConfigError otherwise."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(path, None, "is a folder; expected a file name to write")
    _check_creatable(path, path.parent)
    return path


def writable_dir(path):
    """`path` if outputs can be written into it (nothing is created); ConfigError otherwise."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ConfigError(path, None, "is a file; expected a folder to write into")
    _check_creatable(path, path)
    return path
