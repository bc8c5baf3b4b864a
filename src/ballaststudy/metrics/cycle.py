"""All behaviours of one loading cycle from one snapshot (thesis 4.2.3, l. 935-937: the
metrics are computed "at the end of every loading cycle").

``compute_cycle`` is a compute: a pure function of the snapshot (plain numpy arrays the
rig reads from the engine) that never changes it. The rig calls it once per cycle and
hands the list of results to ``output.write_metrics``.
"""
from dataclasses import dataclass, fields

import numpy as np

from .breakage import breakage_rate, broken_mass_share
from .coordination import coordination_numbers, ghost_particles, in_shoulder, touching_container
from .force_propagation import force_propagation_angle
from .fragments import fragment_centroids, fragments
from .settlement import loading_branch_crossing
from .void_ratio import void_ratio


@dataclass(frozen=True)
class RigGeometry:
    """Box-test geometry at the end of the cycle [m] (y up).

    container_x_min, container_x_max: inner faces of the side walls.
    container_y_bottom: top face of the bottom segments.
    plate_x_mid, plate_bottom_y: the plate's bottom middle point (it moves and may tilt:
        pass its current position).
    plate_half_width: half the plate's width (its x-range for the shoulder area).
    """
    container_x_min: float
    container_x_max: float
    container_y_bottom: float
    plate_x_mid: float
    plate_bottom_y: float
    plate_half_width: float


@dataclass(frozen=True)
class MetricsParams:
    """Settings in SI; ``from_config`` reads the ``metrics:`` section (kN, mm keys)."""
    settlement_force: float = 30e3          # [N] force level of the settlement reading
    fpa_fraction: float = 0.9               # [1] share of a side's bottom force for x90
    ghost_max_contacts: int = 2             # ghost = coordination <= this
    contact_force_threshold: float = 0.0    # [N] a contact carries force if |Fn| > this
    count_plate_contact: bool = True        # the plate counts as one neighbour
    container_tolerance: float = 0.5e-3     # [m] geometric "touches the container"
    shoulder_depth: float = 0.02            # [m] shoulder = centroid above plate bottom - this
    disk_quad_segs: int = 16                # disk polygons: 4 * quad_segs sides
    solid_reuse_tolerance: float = 1e-5     # [m] rigid-fit residual up to which a stone's solid area is reused

    @classmethod
    def from_config(cls, cfg=None):
        cfg = dict(cfg or {})
        conv = {"settlement_force_kN": ("settlement_force", 1e3),
                "contact_force_threshold_N": ("contact_force_threshold", 1.0),
                "container_contact_tolerance_mm": ("container_tolerance", 1e-3),
                "shoulder_depth_mm": ("shoulder_depth", 1e-3),
                "solid_reuse_tolerance_mm": ("solid_reuse_tolerance", 1e-3)}
        kw = {}
        names = {f.name for f in fields(cls)}
        for key, value in cfg.items():
            if key in conv:
                name, scale = conv[key]
                kw[name] = float(value) * scale
            elif key in names:
                kw[key] = value
            else:
                raise KeyError(f"metrics: unknown key {key!r}")
        return cls(**kw)


# what every rig's snapshot holds of its balls, bonds and contacts
PACKING_KEYS = {
    "pos": "(n,2) ball centres [m]",
    "rad": "(n,) ball radii [m]",
    "bond_i": "(m,) ball id", "bond_j": "(m,) ball id",
    "bond_intact": "(m,) bool: bond has at least one intact element",
    "contact_i": "(c,) ball id", "contact_j": "(c,) ball id (ball-ball contacts only)",
    "contact_fn": "(c,) normal force [N]",
    "break_mode": "(r,) 1/'tension' or 2/'shear'",
    "n_elements_per_bond": "int, optional (default 1 = thesis N_r)",
    "cycle_start_step": "int: first step of this cycle",
    "cycle_end_step": "int: first step after this cycle",
    "stone_unit": "(n,) int, optional: the fragment each ball was in when loading began "
                  "(-1: none); with mass, gives broken_mass_share",
    "mass": "(n,) ball masses [kg], optional (real, not density-scaled)",
}

SNAPSHOT_KEYS = {
    **PACKING_KEYS,
    "ballast": "(n,) bool, optional: False for plate pebbles, loading ball, deleted balls",
    "ball_touches_container": "(n,) bool, optional: ball has a contact with a container wall",
    "geometry": "RigGeometry (or a dict of its fields) [m]",
    "bottom_force": "(20,) downward force on each bottom segment [N], compression positive",
    "bottom_x_centre": "(20,) segment mid x [m]", "bottom_width": "(20,) segment length [m]",
    "load_y": "(k,) loading-ball y over the cycle [m]",
    "load_force": "(k,) loading-ball force over the cycle [N]",
    "break_step": "(r,) step of every breakage record so far",
    "n_bonds_installed": "int: flat-joint bonds installed when the stones were built",
}


def compute_cycle(snapshot, params=MetricsParams(), y_reference=None, solid_cache=None):
    """Every per-cycle behaviour from one snapshot dict (keys: ``SNAPSHOT_KEYS``).

    y_reference: the loading ball's y at the settlement force in cycle 0 [m], i.e. the
        ``y_at_level`` this function returned for cycle 0. None means "this is cycle 0"
        (settlement 0 by definition).
    solid_cache: a ``void_ratio.SolidCache`` kept by the caller between cycles, or None.
    Returns a dict of scalars named like the variables of ``output.VARIABLES``.
    """
    s = snapshot
    missing = [k for k, v in SNAPSHOT_KEYS.items() if "optional" not in v and k not in s]
    if missing:
        raise KeyError(f"snapshot lacks {missing}")
    g = s["geometry"]
    g = g if isinstance(g, RigGeometry) else RigGeometry(**g)
    p = params
    out = {}

    # settlement (thesis l. 1036; Fig. 4-2 b reading at 30 kN, l. 802)
    y_c, y_pk, f_pk = loading_branch_crossing(s["load_y"], s["load_force"], p.settlement_force)
    ref = y_c if y_reference is None else float(y_reference)
    out.update(settlement=ref - y_c, displacement_at_peak=ref - y_pk, peak_force=f_pk, y_at_level=y_c)

    # breakage rate (eqs. 4.6-4.8)
    br = breakage_rate(s["break_mode"], s["break_step"], s["n_bonds_installed"],
                       [s["cycle_start_step"], s["cycle_end_step"]], s.get("n_elements_per_bond", 1))
    out.update({k: v[0].item() for k, v in br.items()})

    # force propagation angle (eq. 4.9)
    out.update(force_propagation_angle(s["bottom_force"], s["bottom_x_centre"], s["bottom_width"],
                                       g.plate_x_mid, g.plate_bottom_y, g.container_y_bottom, p.fpa_fraction))

    # fragments = the stones now
    pos = np.asarray(s["pos"], float)
    rad = np.asarray(s["rad"], float)
    nf, labels = fragments(len(rad), s["bond_i"], s["bond_j"], s["bond_intact"], s.get("ballast"))
    out["n_fragments"] = nf
    if "stone_unit" in s:
        out["broken_mass_share"] = broken_mass_share(s["stone_unit"], labels, s["mass"])

    # void ratio (eq. 4.10)
    vr = void_ratio(pos, rad, labels, nf, s["bond_i"], s["bond_j"], s["bond_intact"],
                    g.container_x_min, g.container_x_max, g.container_y_bottom, g.plate_bottom_y,
                    p.disk_quad_segs, solid_cache)
    out.update(void_ratio=vr["void_ratio"], void_ratio_e=vr["void_ratio_e"],
               void_ratio_balls=vr["void_ratio_balls"])

    # coordination number and ghost particles (l. 1065-1074)
    cn = coordination_numbers(labels, nf, s["contact_i"], s["contact_j"], s["contact_fn"],
                              p.contact_force_threshold, p.count_plate_contact)
    wall = touching_container(labels, nf, pos, rad, g.container_x_min, g.container_x_max,
                              g.container_y_bottom, p.container_tolerance,
                              s.get("ball_touches_container"))
    shoulder = in_shoulder(fragment_centroids(labels, nf, pos, rad), g.plate_x_mid,
                           g.plate_half_width, g.plate_bottom_y, p.shoulder_depth) & ~wall
    ghosts = ghost_particles(cn, wall | shoulder, p.ghost_max_contacts)
    out.update(mean_coordination=float(cn.mean()) if nf else np.nan,
               ghost_particles=int(ghosts.sum()),
               excluded_container=int(wall.sum()), excluded_shoulder=int(shoulder.sum()))
    return out
