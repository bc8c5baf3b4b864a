"""Stone placement and deposition, for any container (thesis 4.2.2 a-b): stones drawn from
a BPM library, placed on shelves without interpenetration, dropped under a high gravity
with strengthened bonds, settled, gravity ramped, debris removed.

Everything here works on a ``specimen``: an object with ``sim`` (the Simulation),
``stone_balls()`` (ids of live stone balls) and ``fragments()`` (fragment id per stone
ball); the stone balls are balls 0..n-1, stone ids 0..k-1. A rig adds its container
(walls, plates) around them; nothing here knows about it.
"""
from dataclasses import asdict, dataclass, fields
from typing import ClassVar

import numpy as np

from ..dem import ContactLaw, ContactMaterial, Simulation


# the thesis' equilibrium limit of the mean force ratio (4.2.1, PFC's material-modeling
# default): a body set below it is at rest (stone_force_ratio)
EQUILIBRIUM_FORCE_RATIO = 8e-3

# the rolling sub-model's coefficients: keys only with rolling_resistance epsd
ROLLING_COEFFICIENTS = ("rolling_friction", "rolling_stiffness_ratio", "rolling_damping_ratio")


@dataclass
class DepositionParams:
    """What the kit's stages read (every rig's assembly section has these keys; the values
    are config/thesis.yaml's, which says why). A rig's parameters extend it and name their
    config section ``RIG`` (rig.<RIG>.assembly / .loading)."""
    RIG: ClassVar[str] = ""
    fill_area_ratio: float = 1.0       # ball area of the drawn stones / the specimen's area
    placement_gap_factor: float = 1.1  # shelf cell = factor * the stone's extent
    drop_gravity_m_s2: float = 1000.0
    assembly_friction: float | None = 0.0    # friction while depositing (None: Table 4.2)
    assembly_dt_factor: float = 2.0    # density scaling while depositing: dt = factor x dt_crit
    drop_bond_factor: float = 128.0
    drop_damping: float = 0.7
    drop_check_every: int = 50
    drop_max_steps: int = 400000
    settle_speed_m_s: float = 0.01
    settle_check_every: int = 500
    settle_max_steps: int = 2000000     # a guard (config/thesis.yaml says why)
    gravity_ramp_steps: int = 5000
    min_fragment_balls: int = 3
    gravity_m_s2: float = 9.81
    damping: float = 0.7
    contact_damping_ratio: float = 0.0
    dt_safety: float = 0.8
    # rolling resistance of every contact (the law's rolling sub-model, fixed at assembly):
    # "none" (Table 4.2's linear contact) or "epsd" (Ai et al. 2011 type C, dem/law.py) with
    # mu_r, k_r / (k_s R_r^2) and the rolling dashpot's ratio of critical
    rolling_resistance: str = "none"
    rolling_friction: float = 0.0
    rolling_stiffness_ratio: float = 1.0
    rolling_damping_ratio: float = 0.0

    @classmethod
    def from_config(cls, rig):
        """From the validated ``rig:`` dict: the rig's stages merged (unknown keys are the
        schema's business)."""
        sec = (rig or {}).get(cls.RIG) or {}
        merged = {**(sec.get("assembly") or {}), **(sec.get("loading") or {})}
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in merged.items() if k in names})

    @classmethod
    def from_record(cls, d):
        """From the params a file of ours recorded (an assembled case, a checkpoint): keys
        a later version retired are dropped (the loading a run does comes from its config
        or, resumed, from its saved controllers), new keys take their defaults."""
        names = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in names})

    def to_dict(self):
        return asdict(self)

    def inert_keys(self):
        """The parameters that do not act on a run under the others' values (a cache key
        leaves them out, so runs that differ only in them are one run): none here."""
        return ()

    def first_cycle_inert_keys(self):
        """What cycle 0 does not read (runs that differ only in them share it): none."""
        return ()


def choose_stones(lib, area, rng):
    """Library indices drawn with replacement until their ball area reaches ``area``."""
    picks, total = [], 0.0
    while total < area:
        k = int(rng.integers(len(lib)))
        picks.append(k)
        total += lib.stone(k).area
        if len(picks) > 100000:
            raise ValueError("library stones are too small for the container")
    return picks


def shelf_centres(stones, x_min, x_max, gap_factor, rng):
    """Shelf packing: stones left to right in rows from y = 0, each in a disk of its extent
    times ``gap_factor`` (no interpenetration); every row starts at a random offset so no
    columns form. Returns the centres and the top of the highest row."""
    centres, x, y, row_h = [], None, 0.0, 0.0
    for s in stones:
        e = gap_factor * s.extent
        if x is None or x + 2 * e > x_max:
            y += row_h
            x = x_min + rng.uniform(0.0, 0.5) * e
            row_h = 0.0
        centres.append((x + e, y + e))
        x += 2 * e
        row_h = max(row_h, 2 * e)
    return centres, y + row_h


def new_simulation(lib, params, domain, contact_damping):
    """The engine for a specimen of ``lib``'s stones: drop gravity and damping, Table 4.2's
    contact (with the dashpot ratio ``contact_damping``) for every material pair, with the
    rolling resistance the params switch on."""
    p = params
    sim = Simulation(thickness=lib.thickness, gravity=(0.0, -p.drop_gravity_m_s2),
                     damping=p.drop_damping, dt_safety=p.dt_safety, domain=domain,
                     law=ContactLaw.pfc(rolling=p.rolling_resistance))
    lc = lib.materials[0]["lc"]
    sim.set_contact_material(ContactMaterial(
        E=lc.E, kappa=lc.kappa, mu=lc.mu, beta_n=contact_damping, beta_s=contact_damping,
        mu_r=p.rolling_friction, kr_ratio=p.rolling_stiffness_ratio, eta_r=p.rolling_damping_ratio))
    return sim


def place_stones(sim, lib, stones, centres, rng):
    """Each stone at its centre with a random rotation; stone ids 0..k-1, balls appended
    in stone order. Returns the library's bond count of the stones."""
    n_bonds = 0
    for k, s in enumerate(stones):
        cx, cy = centres[k]
        a = rng.uniform(0, 2 * np.pi)
        ca, sa = np.cos(a), np.sin(a)
        x = cx + ca * s.x - sa * s.y
        y = cy + sa * s.x + ca * s.y
        rho = lib.materials[s.material]["density"]
        sim.add_balls(x, y, s.r, rho, stone_id=k, material_id=s.material)
        n_bonds += len(s.bond_i)
    return n_bonds


def deposition_conditions(specimen, params, mu, on):
    """While dropping and compacting (``on``): friction ``assembly_friction`` for every
    contact (a dense specimen; None keeps Table 4.2's) and density scaling at
    ``assembly_dt_factor`` (only the packing at rest matters there). Off: friction ``mu``
    (Table 4.2) and the real masses. Returns the steps run (one: the first neighbour build
    gives dt_crit)."""
    p, sim = params, specimen.sim
    if not on:
        sim.set_contact_coefficient("mu", mu)
        sim.set_density_scaling(None)
        return 0
    if p.assembly_friction is not None:
        sim.set_contact_coefficient("mu", p.assembly_friction)
    if p.assembly_dt_factor <= 1.0:
        return 0
    sim.run(1)
    sim.set_density_scaling(p.assembly_dt_factor * sim.dt)
    return 1


def ramp_gravity(specimen, g_from, g_to, steps, progress=None):
    """Change gravity geometrically in 20 stages over ``steps`` (damped): an abrupt drop
    from 1000 m/s^2 would release the pile's elastic energy and throw the stones up."""
    sim = specimen.sim
    n = max(1, steps // 20)
    for g in np.geomspace(g_from, g_to, 20):
        sim.set_gravity((0.0, -float(g)))
        sim.run(n)
        if progress is not None:
            progress(n)
    return 20 * n


def stone_force_ratio(specimen):
    """The stones' mean force ratio, PFC's equilibrium measure (thesis 4.2.1) with the stones
    as the bodies: mean over stones of |unbalanced force| over the mean of the sum of the
    magnitudes of the forces on them (contacts with other stones, walls and clumps, and the
    weight). Bond and contact forces inside a stone cancel; local damping, not a force on
    the pile, is left out. 1 for stones in free fall, 0 at rest."""
    sim = specimen.sim
    b = sim.balls
    ids = specimen.stone_balls()
    n = int(b.stone[ids].max()) + 1
    body = np.full(len(b.rad), -1)
    body[ids] = b.stone[ids]
    c = sim.contact_list()
    i, j, f = c["i"], c["j"], np.stack([c["fx"], c["fy"]], axis=1)
    bi = body[i]
    bj = np.where(j >= 0, body[np.maximum(j, 0)], -1)
    outer = bi != bj                                   # contacts between bodies
    unbalanced = np.zeros((n, 2))
    magnitude = np.zeros(n)
    on_j = outer & (bj >= 0)                           # f acts on j (on i for a wall: j < 0)
    on_i = outer & (bi >= 0)
    sign_i = np.where(j >= 0, -1.0, 1.0)
    for k in range(2):
        np.add.at(unbalanced[:, k], bj[on_j], f[on_j, k])
        np.add.at(unbalanced[:, k], bi[on_i], sign_i[on_i] * f[on_i, k])
    size = np.hypot(f[:, 0], f[:, 1])
    np.add.at(magnitude, bj[on_j], size[on_j])
    np.add.at(magnitude, bi[on_i], size[on_i])
    weight = np.bincount(b.stone[ids], b.mass[ids], n)[:, None] * np.asarray(sim.gravity)[None, :]
    unbalanced += weight
    magnitude += np.hypot(weight[:, 0], weight[:, 1])
    live = np.bincount(b.stone[ids], minlength=n) > 0
    return float(np.mean(np.hypot(*unbalanced[live].T)) / np.mean(magnitude[live]))


def settle(specimen, params, stage, progress=None):
    """Run until the mean speed of the stone balls is below ``settle_speed_m_s`` (checked
    every ``settle_check_every`` steps, at most ``settle_max_steps``, a guard): a pile that
    is in equilibrium at a high gravity stays so when the gravity is lowered, while one
    that is still moving would take very long to settle at 9.81 m/s^2 (local damping). On
    thesis-scale piles at 1000 m/s^2 the stones' force ratio is 0.003-0.005 when the speed
    criterion is met, below EQUILIBRIUM_FORCE_RATIO. The end state goes
    to the layout's ``stage_end`` under ``stage``; a pile still moving at the guard also to
    its ``stages_at_limit``. Returns the steps run."""
    p, sim = params, specimen.sim
    steps, speed = 0, np.inf
    while steps < p.settle_max_steps and speed >= p.settle_speed_m_s:
        sim.run(p.settle_check_every)
        steps += p.settle_check_every
        if progress is not None:
            progress(p.settle_check_every)
        ids = specimen.stone_balls()
        speed = float(np.mean(np.hypot(*sim.balls.vel[ids].T)))
    ratio = stone_force_ratio(specimen)
    specimen.layout.stage_end[stage] = {"steps": steps, "speed_m_s": speed, "force_ratio": ratio}
    if speed >= p.settle_speed_m_s:
        specimen.layout.stages_at_limit.append(
            f"{stage}: mean stone-ball speed {speed:.3g} m/s (force ratio {ratio:.3g}) after {steps} "
            f"steps (settle_max_steps; settled below settle_speed_m_s = {p.settle_speed_m_s:g})")
    return steps


def remove_debris(specimen, min_balls):
    """After a cut (``delete_balls``): delete fragments of fewer than ``min_balls`` balls
    that it made out of larger stones (loose single balls would rattle in the voids for a
    long time), then take the deleted balls' bonds out of the bond arrays (every bond loop
    of every later step would pass over them). Returns the number of balls deleted here."""
    sim = specimen.sim
    gone = np.zeros(0, np.int64)
    if min_balls > 1:
        ids = specimen.stone_balls()
        frag = specimen.fragments()
        size = np.bincount(frag[ids])
        stone_size = np.bincount(sim.balls.stone[ids])
        small = size[frag[ids]] < min_balls
        cut = stone_size[sim.balls.stone[ids]] > size[frag[ids]]     # the stone lost balls
        gone = ids[small & cut]
        sim.delete_balls(gone)
    sim.drop_deleted_bonds()
    return len(gone)


def stone_means(specimen, values, n_stones):
    """Per-stone mean of a per-ball quantity over live stone balls (and ball counts)."""
    b = specimen.sim.balls
    ids = specimen.stone_balls()
    st = b.stone[ids]
    n = np.bincount(st, minlength=n_stones)
    s = np.bincount(st, weights=values[ids], minlength=len(n))
    with np.errstate(invalid="ignore", divide="ignore"):
        return s / n, n


def drop(specimen, params, n_stones, progress=None):
    """Free fall under the drop gravity with bonds strengthened by ``drop_bond_factor``
    until the highest stone's mean vertical velocity turns upward (or stops), then settle.
    Returns the steps run."""
    p, sim = params, specimen.sim
    sim.scale_bond_strength(p.drop_bond_factor)
    state = {"fell": False, "landed": False, "steps": 0}

    def watch(s):
        b = s.balls
        ymean, n = stone_means(specimen, b.pos[:, 1], n_stones)
        vmean, _ = stone_means(specimen, b.vel[:, 1], n_stones)
        top = int(np.nanargmax(np.where(n > 0, ymean, -np.inf)))
        v = vmean[top]
        state["steps"] += p.drop_check_every
        if progress is not None:
            progress(p.drop_check_every)
        if v < -1e-3:
            state["fell"] = True
        state["landed"] = state["fell"] and v >= 0.0
        return state["landed"]

    sim.run(p.drop_max_steps, callback=watch, every=p.drop_check_every)
    if not state["landed"]:
        specimen.layout.stages_at_limit.append(
            f"drop: the highest stone still falling after {state['steps']} steps "
            f"(drop_max_steps)")
    return state["steps"] + settle(specimen, p, "settle after the drop", progress)


def centripetal_pulses(specimen, velocity, pulses, steps, half_width, n_stones,
                       progress=None):
    """Compaction like tamping: every stone gets a velocity towards the axis x = 0
    (rigidly, so bonds are not torn) growing with its distance up to ``velocity`` at
    ``half_width``, ``pulses`` times over ``steps``. Returns the steps run."""
    sim = specimen.sim
    pulses = max(1, pulses)
    per = max(1, steps // pulses)
    for _ in range(pulses):
        ids = specimen.stone_balls()
        xm, _ = stone_means(specimen, sim.balls.pos[:, 0], n_stones)
        v = -velocity * np.clip(xm / half_width, -1, 1)
        st = sim.balls.stone[ids]
        vel = sim.balls.vel[ids].copy()
        vel[:, 0] = v[st]
        sim.set_ball_velocity(ids, vel=vel)
        sim.run(per)
        if progress is not None:
            progress(per)
    return pulses * per
