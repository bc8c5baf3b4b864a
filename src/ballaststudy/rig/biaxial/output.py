"""What a finished biaxial run writes: metrics.nc (the kit's cyclic records, the stress and
wall time series, the consolidation and failure attributes) and the specimen figures."""
from pathlib import Path

from ...metrics.output import write_metrics
from ..output import write_figures
from ..records import cyclic_dataset
from .params import KPA

CHANNEL_UNITS = {
    "axial_stress": ("Pa", "axial stress sigma_1 at the top platen (2D: force / (width t))"),
    "left_stress": ("Pa", "stress on the left side wall (2D: force / (height t))"),
    "right_stress": ("Pa", "stress on the right side wall (2D: force / (height t))"),
    "platen_y": ("m", "top platen height"),
    "left_x": ("m", "left side wall x"),
    "right_x": ("m", "right side wall x"),
}


def write_biaxial_outputs(run, out, figures=True, attrs=None):
    """metrics.nc of a biaxial run (+ the specimen figure beside it)."""
    s = run.s
    ds = cyclic_dataset(run, CHANNEL_UNITS, "cyclic biaxial case: per-cycle records and "
                        "behaviours", {"confining_pressure_Pa": run.rig.params.confining_pressure_kPa * KPA,
                                       "height_at_consolidation_m": s.height0,
                                       "width_at_consolidation_m": s.width0,
                                       "stress_convention": "2D stresses: force per boundary "
                                       "length per thickness t; compression positive",
                                       "failed": int(bool(s.failure)), "failure": s.failure,
                                       **(attrs or {})})
    write_metrics(Path(out), ds)
    if figures:
        write_figures(run, ds, out, "biaxial specimen ")
    return ds
