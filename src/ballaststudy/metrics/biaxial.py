"""All behaviours of one cycle of the cyclic biaxial test from one snapshot: breakage rates
(eqs. 4.6-4.8), the permanent axial and volumetric strains, fragments, mean coordination
number and the void ratios of the specimen rectangle between the walls.

``compute_biaxial_cycle`` is a compute, as ``cycle.compute_cycle`` is for the box test: a
pure function of the snapshot (plain numpy arrays the rig reads from the engine) that never
changes it. The rig calls it once per cycle; its results are rows of ``output.VARIABLES``.
"""
from dataclasses import dataclass

import numpy as np

from .breakage import breakage_rate, broken_mass_share
from .coordination import coordination_numbers
from .cycle import PACKING_KEYS, MetricsParams
from .fragments import fragments
from .strain import specimen_strains
from .void_ratio import void_ratio


@dataclass(frozen=True)
class BiaxialGeometry:
    """The specimen rectangle at the end of the cycle [m] (y up): the mean x of each side's
    segments (a membrane's segments differ) and the platens' faces."""
    x_left: float
    x_right: float
    y_bottom: float
    y_top: float


BIAXIAL_SNAPSHOT_KEYS = {
    **PACKING_KEYS,
    "ballast": "(n,) bool: live stone balls",
    "geometry": "BiaxialGeometry (or a dict of its fields) [m]",
    "height": "specimen height between the platens now [m]",
    "width": "mean specimen width between the sides now (area / height) [m]",
    "height0": "height at the end of consolidation [m]", "width0": "width then [m]",
    "break_step": "(r,) step of every breakage record since loading began",
    "n_bonds_installed": "int: flat-joint bonds intact when loading began",
}


def compute_biaxial_cycle(snapshot, params=MetricsParams(), solid_cache=None):
    """Every per-cycle behaviour of the biaxial test from one snapshot dict (keys:
    ``BIAXIAL_SNAPSHOT_KEYS``). ``params``: its contact force threshold, disk polygons;
    ``solid_cache``: a ``void_ratio.SolidCache`` kept by the caller between cycles, or None.
    Returns a dict of scalars named like the variables of ``output.VARIABLES``."""
    s = snapshot
    missing = [k for k, v in BIAXIAL_SNAPSHOT_KEYS.items() if "optional" not in v and k not in s]
    if missing:
        raise KeyError(f"snapshot lacks {missing}")
    g = s["geometry"]
    g = g if isinstance(g, BiaxialGeometry) else BiaxialGeometry(**g)
    p = params

    # breakage rate (eqs. 4.6-4.8), cumulative since loading began
    br = breakage_rate(s["break_mode"], s["break_step"], s["n_bonds_installed"],
                       [s["cycle_start_step"], s["cycle_end_step"]], s.get("n_elements_per_bond", 1))
    out = {k: v[0].item() for k, v in br.items()}

    # permanent strains since the end of consolidation
    ea, ev = specimen_strains(s["height"], s["width"], s["height0"], s["width0"])
    out.update(axial_strain=float(ea), volumetric_strain=float(ev))

    # fragments = the stones now; coordination over ball-ball contacts (no plate here)
    pos = np.asarray(s["pos"], float)
    rad = np.asarray(s["rad"], float)
    nf, labels = fragments(len(rad), s["bond_i"], s["bond_j"], s["bond_intact"], s["ballast"])
    if "stone_unit" in s:
        out["broken_mass_share"] = broken_mass_share(s["stone_unit"], labels, s["mass"])
    cn = coordination_numbers(labels, nf, s["contact_i"], s["contact_j"], s["contact_fn"],
                              p.contact_force_threshold, False)

    # void ratios of the specimen rectangle, stones as solid and balls as solid (eq. 4.10)
    vr = void_ratio(pos, rad, labels, nf, s["bond_i"], s["bond_j"], s["bond_intact"],
                    g.x_left, g.x_right, g.y_bottom, g.y_top, p.disk_quad_segs, solid_cache)
    out.update(n_fragments=int(nf), mean_coordination=float(cn.mean()) if nf else np.nan,
               void_ratio=vr["void_ratio"], void_ratio_e=vr["void_ratio_e"],
               void_ratio_balls=vr["void_ratio_balls"])
    return out
