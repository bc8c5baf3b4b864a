"""The model parameters a calibration may vary (thesis Table 4.2's names), each applied to
an assembled specimen before its loading, so every parameter set reuses the same K
assembled specimens (common random numbers: the sets differ by their parameters only).

F_str_co    strength and cohesion scaling factor: every flat joint's tensile strength and
            cohesion scaled by F_str_co / 3.5 (the BPM libraries are built at Table 4.2's 3.5)
mu          friction coefficient of the linear contact between stones (hard and soft; walls
            and platens keep the rig's)
E_star      effective modulus E* of that contact [Pa] (optional)
kappa_star  its normal-to-shear stiffness ratio kappa* (optional)
(Rolling friction mu_r is not offered: the rigs' contact law has no rolling sub-model.)
"""
import math
from dataclasses import dataclass

from ..dem.materials import F_STR_CO
from ..schema import ConfigError, load_yaml

STONE_MATERIALS = (0, 1)        # hard and soft rock (bpm: material ids of the balls)


@dataclass(frozen=True)
class Parameter:
    name: str
    long_name: str
    units: str
    lowest: float              # physical range: above lowest (strictly if open), up to highest
    highest: float
    open_low: bool = False

    coefficient: str = ""      # the contact law's column it sets (none: F_str_co)

    def table_4_2(self, rig):
        """The value the assembled specimen has (Table 4.2's unless changed)."""
        if not self.coefficient:
            return F_STR_CO
        return float(rig.sim.contact_coefficient(self.coefficient)[0, 0])

    def apply(self, rig, value):
        if not self.coefficient:
            rig.sim.scale_bond_strength(value / F_STR_CO)
        else:
            for a in STONE_MATERIALS:
                for b in STONE_MATERIALS:
                    rig.sim.set_contact_coefficient(self.coefficient, value, a, b)


PARAMETERS = {p.name: p for p in (
    Parameter("F_str_co", "strength and cohesion scaling factor F_str-co (Table 4.2)", "1", 0.0, 1000.0, True),
    Parameter("mu", "friction coefficient of the linear contact between stones (Table 4.2)", "1", 0.0, 10.0,
              coefficient="mu"),
    Parameter("E_star", "effective modulus E* of the linear contact between stones (Table 4.2)", "Pa", 0.0,
              1e12, True, coefficient="E"),
    Parameter("kappa_star", "normal-to-shear stiffness ratio kappa* of that contact (Table 4.2)", "1", 0.0,
              100.0, True, coefficient="kappa"),
)}


def apply_parameters(rig, values):
    """Set ``values`` ({name: value}) on an assembled (not yet loaded) rig."""
    for name, value in values.items():
        PARAMETERS[name].apply(rig, float(value))


def load_calibrated(path):
    """{name: value} of a calibrated.yaml (``ballaststudy calibrate``), each name known and
    each value in its physical range; ConfigError naming file and key otherwise."""
    doc = load_yaml(path)
    values = doc.get("parameters") if isinstance(doc, dict) else None
    if not isinstance(values, dict) or not values:
        raise ConfigError(path, "parameters", "missing; expected the {name: value} of ballaststudy calibrate")
    for name, value in values.items():
        p = PARAMETERS.get(name)
        if p is None:
            raise ConfigError(path, f"parameters.{name}", f"unknown parameter; allowed: {', '.join(PARAMETERS)}")
        ok = (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
              and (value > p.lowest if p.open_low else value >= p.lowest) and value <= p.highest)
        if not ok:
            low = f"> {p.lowest:g}" if p.open_low else f">= {p.lowest:g}"
            raise ConfigError(path, f"parameters.{name}", f"{value!r} is not allowed; allowed: a number {low} and <= {p.highest:g}")
    return {k: float(v) for k, v in values.items()}
