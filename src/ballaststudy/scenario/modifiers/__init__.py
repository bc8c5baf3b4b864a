"""The one registry of modifiers: named changes to an assembled rig (base.py says what one
declares). The material parameters of Table 4.2 (material.py: what a calibration varies)
and the effects the model can gain (what the loop chooses among: each a physical mechanism
in the DEM with one or two parameters, never a correction added to a curve):

    rate           real-time cyclic loading at the test's frequency (true masses, no local
                   damping) with a viscous contact dashpot: inertia and rate-dependent
                   contact dissipation
    abrasion       asperity wear: the bonds of stone balls in the strong force network lose
                   a share of their strength every cycle, so loaded corners weaken and break
    fouling        clay fines coat the stone-stone contacts: friction falls in proportion to
                   the test's void contamination index VCI
    end_restraint  the platens' friction (rough or lubricated ends, an imperfect bedding of
                   the specimen under the platen), a classic triaxial-test effect
    membrane_friction  the sides' friction (a membrane pressed into the surface voids grips
                   the stones; the plain rig's membrane carries no shear)
    fatigue        splitting rigid stones lose strength with the cycles loaded near it
                   (Miner's sum over a Basquin S-N curve): breakage over the long term

A new modifier is one module defining a ``Modifier`` plus one line in MODIFIERS."""
import math

from ...schema import ConfigError, load_yaml
from . import abrasion, end_restraint, fatigue, fouling, material, membrane_friction, rate
from .base import COVARIATES, Modifier, ModifierError, ModifierParameter, covariate  # noqa: F401 (the registry's face)

MODIFIERS = {m.name: m for m in (
    material.F_STR, material.MU, material.E_STAR, material.KAPPA_STAR, material.MU_R,
    rate.MODIFIER, abrasion.MODIFIER, fouling.MODIFIER, end_restraint.MODIFIER,
    membrane_friction.MODIFIER, fatigue.MODIFIER,
)}
MATERIAL = tuple(n for n, m in MODIFIERS.items() if m.role == "material")   # a calibration's parameters
EFFECTS = tuple(n for n, m in MODIFIERS.items() if m.role == "effect")       # the loop's candidates


def material_parameter(name):
    """The ModifierParameter of material modifier ``name`` (units, long name, bounds)."""
    return MODIFIERS[name].parameters[0]


def material_modifiers(values):
    """[(name, {name: value})]: material values {name: value} as single-parameter modifiers."""
    return [(name, {name: float(v)}) for name, v in values.items()]


def load_material_values(path):
    """{name: value} of a calibrated.yaml (``ballaststudy calibrate``), each a material
    modifier's and within its physical range; ConfigError naming file and key otherwise."""
    doc = load_yaml(path)
    values = doc.get("parameters") if isinstance(doc, dict) else None
    if not isinstance(values, dict) or not values:
        raise ConfigError(path, "parameters", "missing; expected the {name: value} of ballaststudy calibrate")
    for name, value in values.items():
        if name not in MATERIAL:
            raise ConfigError(path, f"parameters.{name}", f"unknown parameter; allowed: {', '.join(MATERIAL)}")
        p = material_parameter(name)
        if not (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
                and p.admits(value)):
            raise ConfigError(path, f"parameters.{name}", f"{value!r} is not allowed; allowed: a number {p.range_text()}")
    return {k: float(v) for k, v in values.items()}
