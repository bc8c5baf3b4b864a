"""BPM-building settings (config section ``bpm``) and the Table 4.2 materials they use."""

import json
from dataclasses import asdict, dataclass, replace

from ..dem import DENSITY_HARD, DENSITY_SOFT, ContactMaterial, FlatJointMaterial
from ..dem.materials import F_STR_CO, MATERIAL_NAMES



@dataclass(frozen=True)
class BpmParams:
    """All lengths in m. Defaults = config/thesis.yaml (see the comments there)."""
    radius_min: float = 2.5e-3           # ball radius range of a stone large enough
    radius_max: float = 5.0e-3
    min_balls: int = 10                  # fewest balls a stone should have
    radius_scale_floor: float = 0.4      # smallest scale of the radius range for small stones
    porosity: float = 0.16               # thrown-in disk area = (1 - porosity) * profile area
    force_ratio_limit: float = 8e-3      # stop of the confined relaxation (thesis, PFC md default)
    bonded_cycles: int = 1000            # relaxation after the flat joints are installed
    max_relax_cycles: int = 100_000      # give up the confined relaxation after this many
    check_every: int = 100               # cycles between force-ratio checks
    damping: float = 0.7                 # PFC local damping (material-genesis default)
    packing_friction: float = 0.0        # ball-ball and ball-wall friction while confined
    thickness: float = 1.0               # out-of-plane thickness t (PFC2D)
    max_stones: int | None = None        # None = every stone of the forms file
    batch_balls: int = 1500              # balls per side-by-side simulation
    throw_tries: int = 16                # candidate centres per thrown-in ball

    @classmethod
    def from_config(cls, section):
        """From the validated ``bpm`` config section (mm in the key names)."""
        s = dict(section or {})
        kw = {}
        mm = {"radius_min_mm": "radius_min", "radius_max_mm": "radius_max"}
        for key, value in s.items():
            if key in mm:
                kw[mm[key]] = float(value) * 1e-3
            elif key == "thickness_m":
                kw["thickness"] = float(value)
            else:
                kw[key] = value
        p = cls(**kw)
        if p.radius_min > p.radius_max:
            raise ValueError("radius_min_mm must not exceed radius_max_mm")
        return p

    def as_dict(self):
        return asdict(self)


def flat_joint_materials():
    """{material id: FlatJointMaterial} of Table 4.2 (0 hard, 1 soft)."""
    return {0: FlatJointMaterial.hard(), 1: FlatJointMaterial.soft()}


DENSITIES = (DENSITY_HARD, DENSITY_SOFT)   # Table 4.2 [kg/m3], by material id


def contact_material():
    """The LC model of Table 4.2 (between stones, walls, plate; and unbonded balls)."""
    return ContactMaterial()


def materials_json(params):
    """The parameters used, per material, as JSON (the ``materials_json`` attribute).
    Field names are those of ``ballaststudy.dem.FlatJointMaterial`` / ``ContactMaterial``
    (so ``FlatJointMaterial(**d["hard"]["flat_joint"])`` rebuilds the material; SI units:
    E [Pa], sigma_c [Pa], c [Pa], phi_deg [deg], the rest dimensionless)."""
    lc = contact_material()
    fjs = flat_joint_materials()
    out = {}
    for mid, name in enumerate(MATERIAL_NAMES):
        out[name] = {
            "density_kg_m3": DENSITIES[mid],
            "flat_joint": asdict(fjs[mid]),   # E*, kappa*, sigma_c, c, phi, mu, lambda, g_i factor
            "flat_joint_table_4_2": {"n_elements": 1, "bonded_fraction": 1.0,
                                     "gapped_fraction": 0.0, "initial_surface_gap": 0.0,
                                     "radius_multiplier_code": 0},
            "contact": asdict(lc),                     # LC model: E_n*, kappa_n*, mu_n, dashpots
            "packing_contact": asdict(replace(lc, mu=params.packing_friction)),
        }
    out["F_str_co"] = F_STR_CO
    out["F_str_co_note"] = (
        "multiplies every strength and cohesion (Table 4.2 lists it for both rocks, 4.4): hard "
        "sigma_c = 3.5 * 5.4e5 Pa, c = 3.5 * 60.0e5 Pa; soft sigma_c = 3.5 * 3.0e5 Pa, c = 3.5 * "
        "9.0e5 Pa (ballaststudy.dem.FlatJointMaterial)")
    out["units"] = "SI: E, sigma_c, c in Pa; phi_deg in degrees; density in kg m-3"
    out["source"] = "Wang 2018, Table 4.2 (calibrated parameters)"
    return json.dumps(out, sort_keys=True)
