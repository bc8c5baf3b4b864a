"""The material parameters of thesis Table 4.2 as modifiers (the ones a calibration varies),
each set on an assembled specimen before its loading, so every parameter set reuses the
same K assembled specimens (common random numbers: the sets differ by their values only).

F_str_co    strength and cohesion scaling factor: every flat joint's tensile strength and
            cohesion scaled by F_str_co / 3.5 (the BPM libraries are built at Table 4.2's 3.5)
mu          friction coefficient of the linear contact between stones (hard and soft; walls
            and platens keep the rig's)
E_star      effective modulus E* of that contact [Pa]
kappa_star  its normal-to-shear stiffness ratio kappa*
mu_r        rolling friction of that contact (not in Table 4.2: the specimens must be assembled
            with rig.<kind>.assembly.rolling_resistance epsd; the config check says so)"""
from functools import partial

from ...dem.materials import F_STR_CO, STONE_MATERIALS
from .base import Modifier, ModifierError, ModifierParameter


def _scale_strength(rig, values, covariates):
    rig.sim.scale_bond_strength(values["F_str_co"] / F_STR_CO)


def _strength(rig):
    return {"F_str_co": F_STR_CO}       # the libraries are built at Table 4.2's


def _set_coefficient(column, name, rig, values, covariates):
    if column not in rig.sim.law.coefficients:
        raise ModifierError(name, f"the specimens' contact law {rig.sim.law.names} has no {column}; "
                            f"allowed: specimens assembled with rig.{rig.kind}.assembly.rolling_resistance epsd")
    for a in STONE_MATERIALS:
        for b in STONE_MATERIALS:
            rig.sim.set_contact_coefficient(column, values[name], a, b)


def _coefficient(column, name, rig):
    return {name: float(rig.sim.contact_coefficient(column)[STONE_MATERIALS[0], STONE_MATERIALS[0]])}


def contact_modifier(name, column, long_name, units, low, high, open_low, source="Table 4.2"):
    """A stone-stone contact coefficient (``column`` of the contact law) as a modifier."""
    return Modifier(name, f"{long_name} ({source})",
                    (ModifierParameter(name, f"{long_name} ({source})", units, low, high, open_low),),
                    partial(_set_coefficient, column, name), current=partial(_coefficient, column, name),
                    role="material", needs_rolling=column == "mu_r")


F_STR = Modifier(
    "F_str_co", "flat-joint tensile strength and cohesion scaled by F_str_co / 3.5 (Table 4.2)",
    (ModifierParameter("F_str_co", "strength and cohesion scaling factor F_str-co (Table 4.2)", "1",
                       0.0, 1000.0, True),),
    _scale_strength, current=_strength, role="material", needs_flat_joints=True)
MU = contact_modifier("mu", "mu", "friction coefficient of the linear contact between stones", "1",
                      0.0, 10.0, False)
E_STAR = contact_modifier("E_star", "E", "effective modulus E* of the linear contact between stones",
                          "Pa", 0.0, 1e12, True)
KAPPA_STAR = contact_modifier("kappa_star", "kappa", "normal-to-shear stiffness ratio kappa* of that contact",
                              "1", 0.0, 100.0, True)
MU_R = contact_modifier("mu_r", "mu_r", "rolling friction coefficient mu_r of that contact", "1",
                        0.0, 1.0, False, source="epsd rolling resistance, Ai et al. 2011")
