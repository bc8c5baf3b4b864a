"""Membrane friction: the shear the specimen's sides carry. The biaxial rig's side walls
stand for the triaxial membrane, which transmits no shear (the plain model: the rig's
membrane_friction, 0); a membrane pressed into the voids of coarse ballast under the cell
pressure (membrane penetration) grips the stones at the surface and carries some, which
restrains the specimen's lateral spreading like rough platens restrain its ends. The
parameter is the stone-membrane friction coefficient."""
from ...dem.materials import STONE_MATERIALS
from ...rig.biaxial import MEMBRANE
from .base import Modifier, ModifierParameter


def configure(rig, values, covariates):
    for a in STONE_MATERIALS:
        rig.sim.set_contact_coefficient("mu", values["membrane_friction"], a, MEMBRANE)


MODIFIER = Modifier(
    "membrane_friction", "stone-membrane friction (a membrane pressed into the surface voids grips the stones)",
    (ModifierParameter("membrane_friction", "friction coefficient between stones and the membrane (side walls)",
                       "1", 0.0, 1.0),),
    configure)
