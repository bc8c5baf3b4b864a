"""The netCDF outputs' reference (docs/reference/netcdf.md), written from files the chain
wrote: per kind of file its dimensions, coordinates and variables with their units and
long names as the writers set them, and its global attributes. The test suite keeps the
page honest: every test that makes one of these files checks it against the page
(tests/netcdf_documented.py) and, with BALLASTSTUDY_NETCDF_SAMPLES=DIR, copies it there,
so the page is rewritten from one test run:

    BALLASTSTUDY_NETCDF_SAMPLES=/tmp/nc pytest -m "slow or not slow" -n 2 -k documented_netcdf
    python docs/_ext/netcdf_reference.py /tmp/nc
"""
import re
import sys
from pathlib import Path

import xarray as xr

PAGE = Path(__file__).resolve().parents[1] / "reference" / "netcdf.md"

# kind: (file, what writes it, what it holds); the order of the page
KINDS = {
    "forms": ("results/forms/<database>.nc", "ballaststudy forms generate", "the stones of one database (thesis ch. 3)"),
    "bpm": ("results/bpm/<database>.nc", "ballaststudy bpm build", "the bonded-particle stones of one database (4.2.1)"),
    "assembled": ("results/cases/<database>/case<k>/assembled.nc (a biaxial specimen: any assembled.nc)",
                  "ballaststudy case assemble", "one assembled case: balls, bonds, walls, stones (4.2.2)"),
    "study": ("results/study.nc", "ballaststudy study aggregate", "every case's per-cycle metrics of the study (ch. 5)"),
    "measured": ("results/measured/<set>/<test>.nc", "ballaststudy measured import",
                 "one measured cyclic triaxial test on its cycle axis"),
    "measured_compare": ("results/measured_sim/compare/<set>/<test>.nc", "ballaststudy measured compare",
                         "a measured test beside the cyclic biaxial cases run under its conditions"),
    "strength_case": ("results/strength/<set>/p<p>kPa/case<k>.nc", "ballaststudy case strength",
                      "one monotonic biaxial test to its peak"),
    "strength_envelope": ("results/strength/<set>/envelope.nc", "ballaststudy case envelope",
                          "the strength envelope over confining pressures and specimens"),
    "evaluations": ("results/calibration/<set>/<test>/evaluations.nc", "ballaststudy calibrate",
                    "every evaluated parameter set with its specimens' curves"),
    "posterior": ("results/calibration/<set>/<test>/posterior.nc", "ballaststudy calibrate",
                  "posterior draws of the calibrated parameters"),
    "parametric": ("results/parametric/parametric.nc", "ballaststudy parametric",
                   "the parametric study's final settlement and breakage per set (4.4)"),
    "loop": ("results/loop/loop.nc", "ballaststudy loop", "the loop's measured and model curves and its verdict"),
    "horizon": ("results/horizon/horizon.nc", "ballaststudy horizon",
                "every accumulation law fitted to each measured curve and read at its end"),
}


def _cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def describe(paths):
    """{"dims": {name: size}, "vars": {name: (coord?, dims, units, long_name)}, "attrs": [names]}
    over one or more files of one kind (the union: a variable an option adds is listed)."""
    dims, variables, attrs = {}, {}, set()
    for p in paths:
        with xr.open_dataset(p, decode_times=False) as ds:
            dims.update(ds.sizes)
            for name, v in [*ds.coords.items(), *ds.data_vars.items()]:
                variables.setdefault(name, (name in ds.coords, ", ".join(v.dims), v.attrs.get("units", ""),
                                            v.attrs.get("long_name", "")))
            attrs |= set(ds.attrs)
    return {"dims": dims, "vars": variables, "attrs": sorted(attrs)}


def section(kind, d):
    path, writer, what = KINDS[kind]
    lines = [f"## {kind}", "", f"`{path}`, written by `{writer}`: {what}.", "",
             "Dimensions: " + ", ".join(f"`{k}`" for k in sorted(d["dims"])) + ".", "",
             "| variable | dimensions | units | long name |", "|---|---|---|---|"]
    for name, (coord, dims, units, long_name) in sorted(d["vars"].items(), key=lambda kv: (not kv[1][0], kv[0])):
        label = f"`{name}` (coordinate)" if coord else f"`{name}`"
        lines.append(f"| {label} | {_cell(dims)} | {_cell(units)} | {_cell(long_name)} |")
    lines += ["", "Global attributes: " + ", ".join(f"`{a}`" for a in d["attrs"]) + ".", ""]
    return lines


def page(samples):
    """The page from {kind: [files]}; every kind of KINDS must have a sample."""
    missing = [k for k in KINDS if not samples.get(k)]
    if missing:
        raise SystemExit(f"no sample file of: {', '.join(missing)}")
    lines = ["# netCDF outputs", "",
             "Every netCDF file the chain writes (besides a case's `metrics.nc`: "
             "[its variables](generated/metrics.md)), its variables as the writers set them: open any "
             "with `xr.open_dataset(path)`. Every file is CF (`Conventions`), every variable carries "
             "a `long_name` and every numeric one `units` (`1`: a dimensionless number, a count or "
             "an index; labels such as a database's name have none). Written from the "
             "files of a test run by `docs/_ext/netcdf_reference.py`; every test that makes one of "
             "these files checks it against this page.", ""]
    for kind in KINDS:
        lines += section(kind, describe(samples[kind]))
    return "\n".join(lines)


def documented():
    """{kind: {variable: units}} as the page lists them."""
    out, kind = {}, None
    for line in PAGE.read_text().splitlines():
        if line.startswith("## "):
            kind = line[3:].strip()
            out[kind] = {}
        elif kind and (m := re.match(r"\| `([^`]+)`(?: \(coordinate\))? \| [^|]* \| ([^|]*) \|", line)):
            out[kind][m[1]] = m[2].strip()
    return out


if __name__ == "__main__":
    folder = Path(sys.argv[1])
    samples = {k: sorted(folder.glob(f"{k}__*.nc")) for k in KINDS}
    PAGE.write_text(page(samples))
    print(f"wrote {PAGE} from {sum(map(len, samples.values()))} files")
