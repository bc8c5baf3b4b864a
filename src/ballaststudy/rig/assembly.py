"""Assembling the BPMs in the box (thesis 4.2.2, Fig. 4-8 a-d).

a. random stones from the library (seeded per case), rebuilt on a grid of cells in a tall,
   wide container so that no two stones interpenetrate;
b. free fall under 1000 m/s^2 with bonds strengthened, stopped when the highest stone
   reverses its vertical velocity;
c. balls above the ballast depth deleted, the pressing plate created as a held clump at
   that height, the stones given centripetal velocities so they pack against the plate;
d. balls outside the test's width deleted, side walls moved to the test's width (bottom
   already in 20 segments there), a loading ball on the plate, relaxation steps.

Placement and deposition come from the container-independent kit (deposition.py); this
module adds the box: its walls, the cut at the ballast depth, the plate, the side walls
moved in, the loading ball.
"""
import numpy as np

from ..dem import ContactMaterial
from ..dem.materials import STONE_MATERIALS
from .box import BoxRig, RigLayout
from .deposition import (centripetal_pulses, choose_stones, deposition_conditions, drop,
                         new_simulation, place_stones, ramp_gravity, remove_debris, settle,
                         shelf_centres, stone_force_ratio)

STEEL = 2        # material id of the plate, loading ball and walls (same LC law, Table 4.2)


def build_tall(lib, params, seed, contact_damping=None):
    """Stage a: stones on shelves in the tall container; bonds installed. Returns a BoxRig."""
    p = params
    rng = np.random.default_rng(seed)
    picks = choose_stones(lib, p.fill_area_ratio * p.width_m * p.depth_m, rng)
    stones = [lib.stone(k) for k in picks]
    wt = p.tall_width_factor * p.width_m
    centres, top = shelf_centres(stones, -0.5 * wt, 0.5 * wt, p.placement_gap_factor, rng)
    h_tall = top + p.height_m
    margin = max(0.5 * wt, 0.1)
    sim = new_simulation(lib, p, (-0.5 * wt - margin, -margin, 0.5 * wt + margin,
                                  h_tall + margin),
                         p.contact_damping_ratio if contact_damping is None else contact_damping)
    # the loading ball sits loosely on the plate (not rigidly coupled, thesis 4.1): a softer,
    # damped steel-steel contact so the velocity-controlled ball does not hammer the plate
    lc = lib.materials[0]["lc"]
    sim.set_contact_material(ContactMaterial(E=p.loading_contact_E_Pa, kappa=lc.kappa, mu=lc.mu,
                                             beta_n=p.loading_contact_damping_ratio,
                                             beta_s=p.loading_contact_damping_ratio),
                             STEEL, STEEL)
    lay = RigLayout(seed=int(seed), database=lib.database, library=lib.path,
                    stone_library_index=[int(k) for k in picks],
                    stone_material=[int(s.material) for s in stones])
    # walls: bottom (extension | 20 segments over the test's width | extension), sides
    w2, t2 = 0.5 * p.width_m, 0.5 * wt
    lay.bottom_ext = sim.add_wall([(-t2, 0.0), (-w2, 0.0)], material_id=STEEL).tolist()
    lay.bottom = sim.add_wall([(-w2, 0.0), (w2, 0.0)], segments=p.bottom_segments,
                              material_id=STEEL).tolist()
    lay.bottom_ext += sim.add_wall([(w2, 0.0), (t2, 0.0)], material_id=STEEL).tolist()
    lay.left = sim.add_wall([(-t2, h_tall), (-t2, p.height_m), (-t2, 0.0)],
                            material_id=STEEL).tolist()
    lay.right = sim.add_wall([(t2, 0.0), (t2, p.height_m), (t2, h_tall)],
                             material_id=STEEL).tolist()
    lay.left_low, lay.right_low = lay.left[1], lay.right[0]
    lay.bonds_library = place_stones(sim, lib, stones, centres, rng)
    lay.n_stone_balls = len(sim.balls)
    fj = {m: lib.materials[m]["fj"] for m in STONE_MATERIALS}
    lay.bonds_installed = int(sim.install_flat_joints(fj))
    return BoxRig(sim, lay, p)


def tamp(rig, progress=None):
    """Stage c: tamping-like compaction and the plate. Every stone gets a centripetal
    velocity towards the axis x = 0 (rigidly, so bonds are not torn), ``tamping_pulses``
    times, under ``tamping_gravity``; balls reaching above the ballast depth are deleted
    and the pressing plate is created as a held clump at the depth: after the tamping by
    default (compacting first makes the remaining layer as deep as the test's 18 cm
    instead of settling below it), before it with ``tamping_against_plate`` (the thesis'
    order: the stones "rush against" the held plate, 4.2.2 c)."""
    p, lay = rig.params, rig.layout
    if p.tamping_against_plate:
        place_plate(rig)
    done = ramp_gravity(rig, p.drop_gravity_m_s2, p.tamping_gravity_m_s2, p.gravity_ramp_steps,
                        progress)
    done += centripetal_pulses(rig, p.tamping_velocity_m_s, p.tamping_pulses, p.tamping_steps,
                               0.5 * p.width_m * p.tall_width_factor,
                               len(lay.stone_library_index), progress)
    done += settle(rig, p, "settle after tamping", progress)
    if not p.tamping_against_plate:
        place_plate(rig)
    return done


def place_plate(rig):
    """Balls reaching above the ballast depth deleted (and the debris that makes), the
    pressing plate created at the depth as a held clump."""
    p, sim, lay = rig.params, rig.sim, rig.layout
    b = sim.balls
    ids = rig.stone_balls()
    sim.delete_balls(ids[b.pos[ids, 1] + b.rad[ids] > p.depth_m])
    remove_debris(rig, p.min_fragment_balls)
    # plate: a row of overlapping pebbles (radius = half the thickness, spacing = radius)
    rp = 0.5 * p.plate_thickness_m
    n = max(2, int(round((p.plate_width_m - 2 * rp) / rp)) + 1)
    px = np.linspace(-0.5 * p.plate_width_m + rp, 0.5 * p.plate_width_m - rp, n)
    py = np.full(n, p.depth_m + rp)
    # mass/inertia of the solid rectangle (the pebble sums would count overlaps twice)
    m = p.plate_density_kg_m3 * p.plate_width_m * p.plate_thickness_m * sim.thickness
    inertia = m * (p.plate_width_m ** 2 + p.plate_thickness_m ** 2) / 12.0
    n0 = len(sim.balls)
    lay.plate = int(sim.add_clump(px, py, np.full(n, rp), p.plate_density_kg_m3, held=True,
                                  material_id=STEEL, mass=m, inertia=inertia))
    lay.plate_balls = list(range(n0, len(sim.balls)))
    sim.set_clump_velocity(lay.plate, vel=(0.0, 0.0), omega=0.0, held=True)


def move_side_walls(rig, progress=None):
    """Stage d (first half): delete balls outside the test's width, then move the side
    walls kinematically to x = -/+ width/2 (nothing is in their way any more)."""
    p, sim, lay = rig.params, rig.sim, rig.layout
    b = sim.balls
    ids = rig.stone_balls()
    w2 = 0.5 * p.width_m
    out = (b.pos[ids, 0] - b.rad[ids] < -w2) | (b.pos[ids, 0] + b.rad[ids] > w2)
    sim.delete_balls(ids[out])
    remove_debris(rig, p.min_fragment_balls)
    steps = 0
    for _ in range(200):
        xl = sim.walls.seg[lay.left[0], 0]
        xr = sim.walls.seg[lay.right[0], 0]
        gap = max(abs(-w2 - xl), abs(xr - w2))
        if gap < 1e-9:
            break
        dt = sim.dt if sim.dt > 0 else 1e-6
        n = max(1, min(1000, int(np.ceil(gap / (p.wall_speed_m_s * dt)))))
        sim.set_wall_velocity(lay.left, vel=((-w2 - xl) / (n * dt), 0.0))
        sim.set_wall_velocity(lay.right, vel=((w2 - xr) / (n * dt), 0.0))
        sim.run(n)
        steps += n
        if progress is not None:
            progress(n)
    sim.set_wall_velocity(lay.left, vel=(0.0, 0.0))
    sim.set_wall_velocity(lay.right, vel=(0.0, 0.0))
    return steps


def settle_plate(rig, progress=None):
    """Stage d: lower the held plate onto the stones (the tamped surface may lie below the
    cut at the ballast depth): fast to within ``plate_approach_gap_m`` of the highest
    stone ball under it (geometric gap), then at ``plate_settle_velocity_m_s`` until the
    stones carry its weight (at most 10000 moves; a plate still not carried is recorded in
    the layout's ``stages_at_limit``). The slow speed is above ``settle_speed_m_s``
    (config.ORDERED_PAIRS): a settled pile's surface still moves at about that speed, and a
    plate no faster follows it down. Returns the steps run."""
    p, sim, lay = rig.params, rig.sim, rig.layout
    c = lay.plate
    b = sim.balls
    ids = rig.stone_balls()
    m = float(sim.clumps.mass[c])
    steps = 0
    for _ in range(10000):
        pb = np.asarray(lay.plate_balls)
        bottom = (b.pos[pb, 1] - b.rad[pb]).min()
        under = np.abs(b.pos[ids, 0]) < 0.5 * p.plate_width_m + b.rad[ids]
        top = (b.pos[ids[under], 1] + b.rad[ids[under]]).max() if under.any() else 0.0
        gap = bottom - top
        f, _ = sim.clump_force(c)
        carried = f[1] - m * sim.gravity[1]
        if carried >= m * p.gravity_m_s2:      # in contact (its weight at 9.81 m/s^2)
            break
        dt = sim.dt if sim.dt > 0 else 1e-6
        if gap > p.plate_approach_gap_m:
            n = max(1, min(2000, int((gap - 0.5 * p.plate_approach_gap_m) / (p.wall_speed_m_s * dt))))
            v = (gap - 0.5 * p.plate_approach_gap_m) / (n * dt)
        else:
            n, v = p.control_every, p.plate_settle_velocity_m_s
        sim.set_clump_velocity(c, vel=(0.0, -v), omega=0.0, held=True)
        sim.run(n)
        steps += n
        if progress is not None:
            progress(n)
    else:
        f, _ = sim.clump_force(c)
        lay.stages_at_limit.append(
            f"plate: the stones carry {f[1] - m * sim.gravity[1]:.3g} N of its "
            f"{m * p.gravity_m_s2:.3g} N weight after {steps} steps (10000 moves)")
    sim.set_clump_velocity(c, vel=(0.0, 0.0), omega=0.0, held=True)
    return steps


def add_loading_ball(rig):
    """A ball on top of the plate at its centre (the loading element of the test)."""
    p, sim, lay = rig.params, rig.sim, rig.layout
    c = lay.plate
    cx, cy = sim.clumps.pos[c]
    top = max(sim.balls.pos[i, 1] + sim.balls.rad[i] for i in lay.plate_balls)
    r = p.loading_ball_radius_m
    n0 = len(sim.balls)
    lay.loading = int(sim.add_clump([cx], [top + r], [r], p.loading_ball_density_kg_m3,
                                    material_id=STEEL))
    lay.loading_ball = n0


def relax(rig, progress=None):
    """Stage d (second half): bonds back to their Table 4.2 strength (the factor is a power
    of two in the default config, so this is exact), plate released, loading ball resting
    on it, periods of ``relax_steps`` steps (the thesis' 10,000 cycles) with normal gravity
    and loading damping until the stones' force ratio is at most ``relax_force_ratio``
    (4.2.1's balancing limit; 1: one period), at most ``settle_max_steps`` (a guard: a layer
    still above the limit is recorded in the layout's ``stages_at_limit``). 10,000 of our
    steps leave a thesis-scale layer at 5 x the limit (docs/how-to/thesis-scale.md). The
    end state goes to the layout's ``stage_end["relax"]``. Returns the steps run."""
    p, sim, lay = rig.params, rig.sim, rig.layout
    # ramp to normal gravity with the plate and loading ball on (strengthened bonds, drop
    # damping), then bonds back to their strength and loading damping
    ramped = ramp_gravity(rig, p.tamping_gravity_m_s2, p.gravity_m_s2, p.gravity_ramp_steps,
                          progress)
    sim.scale_bond_strength(1.0 / p.drop_bond_factor)
    sim.set_damping(p.damping, clump_alpha=p.damping)
    sim.set_clump_velocity(lay.plate, held=False)
    done = 0
    while True:
        done += _relax_period(sim, p.relax_steps, progress)
        ratio = stone_force_ratio(rig)
        if ratio <= p.relax_force_ratio or done >= p.settle_max_steps:
            break
    lay.stage_end["relax"] = {"steps": done + ramped, "force_ratio": ratio}
    if ratio > p.relax_force_ratio:
        lay.stages_at_limit.append(
            f"relax: the stones' force ratio {ratio:.3g} after {done} steps (settle_max_steps; "
            f"relaxed to relax_force_ratio = {p.relax_force_ratio:g})")
    return done + ramped


def _relax_period(sim, steps, progress):
    """``steps`` steps in 20 chunks (progress after each)."""
    chunk, done = max(1, steps // 20), 0
    while done < steps:
        k = min(chunk, steps - done)
        sim.run(k)
        done += k
        if progress is not None:
            progress(k)
    return steps


def assemble(lib, params, seed, progress=None):
    """All of 4.2.2: returns the relaxed BoxRig (loading ball not yet loaded)."""
    rig = build_tall(lib, params, seed)
    st = rig.layout.stage_steps
    mu = lib.materials[0]["lc"].mu
    n_stones = len(rig.layout.stone_library_index)
    st["drop"] = (deposition_conditions(rig, params, mu, on=True)
                  + drop(rig, params, n_stones, progress))
    st["tamping"] = tamp(rig, progress)
    deposition_conditions(rig, params, mu, on=False)
    st["reset"] = move_side_walls(rig, progress)
    # the thesis' order leaves the plate where the tamping held it, at the depth: it meets the
    # settled stones when released (its "void under the plate", 4.3)
    st["plate"] = 0 if params.tamping_against_plate else settle_plate(rig, progress)
    add_loading_ball(rig)
    st["relax"] = relax(rig, progress)
    return rig
