"""Abrasion: asperity wear of the stones under high contact force, accumulating over
cycles. At the end of every cycle the stone balls that carry a contact of the strong force
network - a normal force above the mean of all stone-stone contacts (Radjai et al. 1998,
the network that carries the load) - lose the share ``wear_per_cycle`` (the parameter) of
the tensile strength and cohesion of every flat joint they are part of. Loaded corners
weaken cycle after cycle and break off at loads they first carried; the damage is the
joint strengths themselves, so checkpoints carry it."""
import numpy as np

from .base import Modifier, ModifierParameter


def strong_balls(rig):
    """Ids of the stone balls with a stone-stone contact above the mean normal force."""
    i, j, fn = rig.ball_contacts()
    n = rig.layout.n_stone_balls
    stone = rig.sim.balls.stone
    between = (i < n) & (j < n) & (stone[i] != stone[j])
    if not between.any():
        return np.zeros(0, int)
    strong = between & (fn > fn[between].mean())
    return np.unique(np.concatenate([i[strong], j[strong]]))


def wear(rig, share):
    """Every flat joint of a strong-network ball loses ``share`` of its strengths (once
    per call, however many of its balls are strong). Returns the joints worn."""
    bonds, strong = rig.sim.bonds, strong_balls(rig)
    hit = np.nonzero(np.isin(bonds.i, strong) | np.isin(bonds.j, strong))[0]
    rig.sim.scale_bond_strength(1.0 - share, hit)
    return hit


def hook(values):
    share = values["wear_per_cycle"]

    def end_of_cycle(run, cycle):
        wear(run.rig, share)
    return end_of_cycle


MODIFIER = Modifier(
    "abrasion", "flat joints of stone balls in the strong force network lose a share of their "
    "strength every cycle",
    (ModifierParameter("wear_per_cycle", "share of a loaded joint's strength lost per cycle", "1", 0.0, 0.2),),
    hook=hook, needs_flat_joints=True, off=lambda material: {"wear_per_cycle": 0.0})
