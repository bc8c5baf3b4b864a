"""Fatigue of splitting rigid stones: strength that falls with the load history, the
long-term breakage the bonded stones cannot reach (Ergenzinger et al. accumulate damage
bond by bond, thesis eq. 2.10-2.11; here it is the stone's). Miner's linear sum over a
Basquin S-N curve N_f(r) = r^-b, r the cycle's largest characteristic stress over the
stone's drawn strength: every cycle a stone loaded above the endurance ratio gains r^b of
damage D, and it splits once its load reaches strength (1 - D) (dem/crushing.py). b is the
S-N curve's slope in log-log (large: damage only near the strength), the endurance ratio
the load below which a stone takes no damage. The damage is engine state (Clumps.damage),
so checkpoints carry it."""
from .base import Modifier, ModifierParameter


def hook(values):
    exponent, endurance = values["fatigue_exponent"], values["endurance_ratio"]

    def end_of_cycle(run, cycle):
        run.rig.sim.accumulate_damage(exponent, endurance)
    return end_of_cycle


MODIFIER = Modifier(
    "fatigue", "splitting stones lose strength with each cycle loaded near it (Miner's sum, "
    "Basquin S-N curve)",
    (ModifierParameter("fatigue_exponent", "slope b of the S-N curve N_f = (stress/strength)^-b",
                       "1", 1.0, 200.0),
     ModifierParameter("endurance_ratio", "stress/strength ratio below which a cycle does no damage",
                       "1", 0.0, 0.95)),
    hook=hook, needs_splitting=True)
