"""End restraint and bedding under the platens: how rough the specimen's ends are held. A
triaxial specimen's ends sit on the platens through an imperfect bedding; rough ends
restrain the lateral spreading of the end zones, lubricated or poorly bedded ones let the
stones slide out (a classic source of differences between triaxial tests). The parameter is
the stone-platen friction coefficient (the plain model: Table 4.2's stone friction)."""
from ...dem.materials import STONE_MATERIALS, ContactMaterial
from ...rig.biaxial import PLATEN
from .base import Modifier, ModifierParameter



def configure(rig, values, covariates):
    for a in STONE_MATERIALS:
        rig.sim.set_contact_coefficient("mu", values["platen_friction"], a, PLATEN)


MODIFIER = Modifier(
    "end_restraint", "stone-platen friction (rough, lubricated or poorly bedded specimen ends)",
    (ModifierParameter("platen_friction", "friction coefficient between stones and platens", "1", 0.0, 1.2),),
    configure, off=lambda material: {"platen_friction": material.get("mu", ContactMaterial().mu)})
