"""Fouling: clay fines in the voids coat the stone-stone contacts (Tennakoon & Indraratna
2014 grade it by the void contamination index VCI, the fines' share of the void volume).
The contact sub-model between stones changes with the fines content: its friction
coefficient falls in proportion to VCI,

    mu_fouled = mu (1 - loss VCI / 100),

loss (the parameter) being the friction a fully clogged void structure takes away. Tests
that declare no VCI are clean (VCI = 0): the effect leaves them unchanged."""
from ...dem.materials import STONE_MATERIALS
from .base import Modifier, ModifierParameter, covariate



def configure(rig, values, covariates):
    factor = 1.0 - values["friction_loss"] * covariate(covariates, "VCI") / 100.0
    mu = rig.sim.contact_coefficient("mu")
    for a in STONE_MATERIALS:
        for b in STONE_MATERIALS:
            rig.sim.set_contact_coefficient("mu", mu[a, b] * factor, a, b)


MODIFIER = Modifier(
    "fouling", "stone-stone friction reduced in proportion to the void contamination index VCI",
    (ModifierParameter("friction_loss", "share of the stone-stone friction lost at VCI = 100 %",
                     "1", 0.0, 0.9),),
    configure, covariate="VCI", off=lambda material: {"friction_loss": 0.0})
