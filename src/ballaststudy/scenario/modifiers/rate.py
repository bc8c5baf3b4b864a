"""Loading rate and inertia: the biaxial rig's real-time mode at the test's frequency (true
masses, sinusoidal deviator) instead of quasi-static loading, with the PFC local damping
off - a numerical device for quasi-static runs that would swallow the inertia - and energy
dissipated by friction, breakage and a viscous normal dashpot at every stone contact,
whose damping ratio (of critical) is the parameter: the contact's own rate dependence."""
from ...dem.materials import STONE_MATERIALS
from .base import Modifier, ModifierParameter


def configure(rig, values, covariates):
    sim = rig.sim
    sim.set_damping(0.0, clump_alpha=0.0)       # rigid stones too (their clumps)
    for a in STONE_MATERIALS:
        for b in range(sim.coef.shape[0]):
            sim.set_contact_coefficient("beta_n", values["contact_damping_ratio"], a, b)


MODIFIER = Modifier(
    "rate", "real-time loading at the test's frequency (inertia) with a viscous normal dashpot "
    "at the stone contacts, no local damping",
    (ModifierParameter("contact_damping_ratio", "normal dashpot damping ratio of the stone contacts",
                     "1", 0.05, 0.7),),
    configure, rig_settings=(("mode", "real_time"),))     # at the test's f (take_conditions)
