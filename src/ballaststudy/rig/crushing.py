"""Single-stone crushing between two platens: the strength of a library's stones under
either stone model, and the Weibull law fitted to it (the rigid stones' strength
calibrated against the bonded stones', not guessed), in the stress of either splitting
criterion (dem/crushing.py CRITERIA).

A stone of the library, turned by a seeded random angle, lies between two flat platens
that close at ``platen_speed_m_s`` each, gravity off, local damping on (quasi-static: the
closing takes ~10^3 times a wave's transit through the stone). Its stress is the
criterion's, from the platens' forces on the whole stone exactly as the splitting kernel
computes it for a clump (crushing.stone_loads / characteristic_stress): F / (d t) with F
the larger platen resultant (friction included), d = sqrt(4 A / pi) with A the pebble-sum
area, t the thickness; or the deviator of (1/(A t)) sum f (x) r over the platen contacts.
Bonded stones' inner forces (contacts, flat joints) do not enter: one body. It has failed when the
largest piece holds less than ``intact_share`` of the stone's mass (one rule for both
models: a bonded stone cracks element by element and chips first, a rigid one splits at
once; a rule on the platen force's drop was tried and fired on stones that rock on their
first contact); sigma_f is the peak stress up to then (the forces read are those of the
last step, computed before a split). A stone closed to
``max_strain`` without failing is right-censored.

The fit: survival exp(-(d/d0)^2 (sigma/sigma0)^m) (dem/crushing.py's law), by maximum
likelihood over the failed and the censored stones, with the profile-likelihood 90 %
interval of m (chi-square, 1 degree of freedom).
"""
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from ..dem import ContactLaw, Simulation
from ..dem.crushing import CRITERIA, characteristic_stress, stone_loads
from ..dem.materials import F_STR_CO, STONE_MATERIALS
from ..stones import stone_model


@dataclass
class CrushingParams:
    platen_speed_m_s: float = 0.01    # each platen (0.05 changed bonded strengths by up to 30 %)
    damping: float = 0.7              # local damping (quasi-static)
    clearance_m: float = 1e-4         # gap between the stone and each platen at the start
    intact_share: float = 0.9         # failed: the largest piece below this share of the mass
    max_strain: float = 0.3           # censored: closed by this share of the stone's height
    chunk_steps: int = 50             # bonded: failure looked for after each chunk (rigid:
                                      # after each stress check: the peak is the split's force)
    F_str_co: float = F_STR_CO        # flat joints: their strength factor (Table 4.2: 3.5)
    check_every_steps: int = 10       # rigid: stresses checked every this many steps
    criterion: str = CRITERIA[0]      # the stress measured (and split on; dem/crushing.py)


@dataclass
class Crush:
    stone: int          # library index
    diameter: float     # equivalent diameter d (pebble-sum area) [m]
    force: float        # peak platen force up to failure [N]
    stress: float       # sigma_f: the criterion's peak stress up to failure [Pa]
    failed: bool        # False: censored at max_strain
    steps: int
    drawn: float = float("nan")   # rigid: the strength the stone drew (dem/crushing.py) [Pa]


def _platen_sim(lib, k, angle, params):
    """The engine with stone ``k`` turned by ``angle`` at the origin between two platens."""
    s = lib.stone(k)
    ca, sa = np.cos(angle), np.sin(angle)
    x, y = ca * s.x - sa * s.y, sa * s.x + ca * s.y
    span = 2.0 * s.extent
    sim = Simulation(thickness=lib.thickness, gravity=(0.0, 0.0), damping=params.damping,
                     domain=(-3 * span, -3 * span, 3 * span, 3 * span), law=ContactLaw.pfc())
    sim.set_contact_material(lib.materials[0]["lc"])
    ids = sim.add_balls(x, y, s.r, lib.materials[s.material]["density"], stone_id=0,
                        material_id=s.material)
    sim.install_flat_joints({m: lib.materials[m]["fj"] for m in STONE_MATERIALS})
    top_y = float((y + s.r).max()) + params.clearance_m
    bottom_y = float((y - s.r).min()) - params.clearance_m
    top = sim.add_wall([(-span, top_y), (span, top_y)])
    bottom = sim.add_wall([(span, bottom_y), (-span, bottom_y)])
    sim.set_wall_velocity(top, vel=(0.0, -params.platen_speed_m_s))
    sim.set_wall_velocity(bottom, vel=(0.0, params.platen_speed_m_s))
    return sim, ids, top, top_y - bottom_y, span


def crush(lib, k, model, params=CrushingParams(), seed=0, splitting=None):
    """Crush stone ``k`` of ``lib`` under the stone model named ``model`` (``splitting``:
    the Weibull of stones that split, dict(sigma0, m, d0), on params.criterion's stress).
    Returns a Crush."""
    rng = np.random.default_rng([int(seed), int(k)])
    angle = rng.uniform(0.0, 2.0 * np.pi)
    stream_seed = int(rng.integers(2 ** 53))    # each stone its own strength stream
    sim, ids, top, height, span = _platen_sim(lib, k, angle, params)
    stones = stone_model(model)
    if stones.has_flat_joints:
        sim.scale_bond_strength(params.F_str_co / F_STR_CO)
    split = None if splitting is None else dict(seed=stream_seed, fines_diameter=0.0, criterion=params.criterion,
                                                every=params.check_every_steps, **splitting)
    stones.make(sim, ids, split)
    d = 2.0 * float(np.sqrt((sim.balls.rad[ids] ** 2).sum()))
    mass = sim.balls.mass[ids]
    peak, force, closed, failed = 0.0, 0.0, 0.0, False
    chunk = params.check_every_steps if split else params.chunk_steps
    while closed < params.max_strain * height:
        sim.run(chunk)
        b = sim.balls
        sim.delete_balls(np.flatnonzero((b.alive == 1) & (np.hypot(*b.pos.T) > span)))   # chips thrown off
        closed = 2.0 * params.platen_speed_m_s * sim.time
        labels = stones.fragments(sim, len(ids))
        largest = np.bincount(labels[labels >= 0], weights=mass[labels >= 0]).max(initial=0.0)
        # the forces of the chunk's last step: before any split
        peak = max(peak, stone_stress(sim, ids, params.criterion))
        force = max(force, float(np.hypot(*sim.wall_force(top).sum(axis=0))))
        if largest < params.intact_share * mass.sum():
            failed = True
            break
    drawn = float("nan")                  # a stone that splits: the strength it drew
    if len(sim.splits):
        drawn = float(sim.splits.strength[0])
    elif split:
        drawn = float(sim.clumps.strength[0])
    return Crush(int(k), d, force, peak, failed, sim.step, drawn)


def stone_stress(sim, ids, criterion):
    """The ``criterion``'s stress of the stone made of balls ``ids`` (all of them one body,
    whatever its clumps or bonds) from the forces of the last step [Pa]."""
    b = sim.balls
    live = ids[b.alive[ids] == 1]
    body = np.full(len(b.rad), -1, np.int32)
    body[live] = 0
    centre = (b.mass[live, None] * b.pos[live]).sum(axis=0) / b.mass[live].sum()
    kin = np.column_stack([b.pos, b.vel, b.omega, b.rad, b.minv, b.mat])
    fmax, s, area = stone_loads(sim.thickness, kin, body, b.alive, sim.pairs.kernel(),
                                sim.wpairs.kernel(), sim.walls.seg, centre[None, :])
    return float(characteristic_stress(sim.thickness, fmax, s, area, CRITERIA.index(criterion))[0])


def weibull_fit(stress, diameter, failed, d0):
    """Maximum-likelihood (sigma0, m) of survival exp(-(d/d0)^2 (sigma/sigma0)^m) over
    failures at ``stress`` and censored stones (failed False) survived to it, and the
    profile-likelihood 90 % interval of m. Returns dict(sigma0, m, m_low, m_high, n)."""
    s, d, f = (np.asarray(a, float) for a in (stress, diameter, failed))
    if not (s > 0).all() or not f.any():
        raise ValueError("weibull_fit: every stress must be > 0 and at least one stone must fail")
    ref = float(np.median(s))          # stresses in units of their median: no overflow
    s = s / ref
    w = (d / d0) ** 2

    def nll(m, log_s0):
        log_f = np.log(w) + np.log(m) + (m - 1) * np.log(s) - m * log_s0
        return -((f * log_f).sum() - (w * np.exp(m * (np.log(s) - log_s0))).sum())

    def best_scale(m):     # log sigma0 given m, in closed form: sigma0^m = sum w s^m / n_failed
        return (np.log((w * np.exp(m * np.log(s) - m * np.log(s).max())).sum() / f.sum())
                + m * np.log(s).max()) / m

    def profile(m):
        return nll(m, best_scale(m))

    res = optimize.minimize_scalar(profile, bounds=(0.1, 100.0), method="bounded")
    m_hat = float(res.x)
    cut = res.fun + 0.5 * stats.chi2.ppf(0.9, 1)
    low = optimize.brentq(lambda m: profile(m) - cut, 0.05, m_hat) if profile(0.05) > cut else 0.05
    high = optimize.brentq(lambda m: profile(m) - cut, m_hat, 200.0) if profile(200.0) > cut else 200.0
    return dict(sigma0=ref * float(np.exp(best_scale(m_hat))), m=m_hat, m_low=float(low),
                m_high=float(high), n=int(len(s)), n_failed=int(f.sum()), d0=float(d0))
