"""Assembling the biaxial specimen: stones on shelves in a tall box of the specimen's width
(kit: deposition.py), dropped, the balls above the specimen height cut, the top platen set
on the highest stone, the membrane (if any) spanning the platens, relaxation."""
import numpy as np

from ...dem.materials import STONE_MATERIALS
from ..deposition import (choose_stones, deposition_conditions, drop, new_simulation,
                          place_stones, ramp_gravity, remove_debris, shelf_centres,
                          stone_force_ratio)
from .specimen import MEMBRANE, PLATEN, BiaxialLayout, BiaxialRig, place_membrane


def build_specimen(lib, params, seed):
    """Stones on shelves in a tall box of the specimen's width (bottom platen at y = 0,
    side walls reaching well above the shelves); bonds installed."""
    p = params
    rng = np.random.default_rng(seed)
    picks = choose_stones(lib, p.fill_area_ratio * p.width_m * p.height_m, rng)
    stones = [lib.stone(k) for k in picks]
    w2 = 0.5 * p.width_m
    centres, top = shelf_centres(stones, -w2, w2, p.placement_gap_factor, rng)
    h_tall = top + p.height_m
    margin = max(p.width_m, 0.1)
    sim = new_simulation(lib, p, (-w2 - margin, -margin, w2 + margin, h_tall + margin),
                         p.contact_damping_ratio)
    lay = BiaxialLayout(seed=int(seed), database=lib.database, library=lib.path,
                        stone_library_index=[int(k) for k in picks],
                        stone_material=[int(s.material) for s in stones])
    wide = 0.6 * p.width_m       # platens reach past the side walls as these move in
    lay.bottom = sim.add_wall([(-w2 - wide, 0.0), (w2 + wide, 0.0)], material_id=PLATEN).tolist()
    n = p.membrane_segments
    ys = [h_tall] + ([] if n == 1 else list(np.linspace(p.height_m, 0.0, n + 1))) + [-0.05 * p.height_m]
    lay.left = sim.add_wall([(-w2, y) for y in ys], material_id=MEMBRANE).tolist()
    lay.right = sim.add_wall([(w2, y) for y in ys[::-1]], material_id=MEMBRANE).tolist()
    if n > 1:
        lay.left_groups = membrane_groups(lay.left[::-1])
        lay.right_groups = membrane_groups(lay.right)
    lay.bonds_library = place_stones(sim, lib, stones, centres, rng)
    lay.n_stone_balls = len(sim.balls)
    lay.bonds_installed = int(sim.install_flat_joints({m: lib.materials[m]["fj"]
                                                      for m in STONE_MATERIALS}))
    return BiaxialRig(sim, lay, p)


def membrane_groups(chain):
    """Servo groups of a membrane chain given bottom up (extension below, n segments,
    extension above): the membrane segment first, the extensions with the end segments."""
    groups = [[k] for k in chain[1:-1]]
    groups[0].append(chain[0])
    groups[-1].append(chain[-1])
    return groups


def wall_friction(rig, mu):
    """Platens: ``mu`` (Table 4.2's); side walls: the membrane's."""
    sim = rig.sim
    for m in STONE_MATERIALS:
        sim.set_contact_coefficient("mu", mu, m, PLATEN)
        sim.set_contact_coefficient("mu", rig.params.membrane_friction, m, MEMBRANE)


def assemble_biaxial(lib, params, seed, progress=None):
    """Deposition, the cut at the specimen height, the top platen on the highest stone,
    relaxation at normal gravity. Returns the BiaxialRig (not yet consolidated)."""
    rig = build_specimen(lib, params, seed)
    p, sim, lay, st = params, rig.sim, rig.layout, rig.layout.stage_steps
    mu = lib.materials[0]["lc"].mu
    n_stones = len(lay.stone_library_index)
    st["drop"] = (deposition_conditions(rig, p, mu, on=True)
                  + drop(rig, p, n_stones, progress))
    st["gravity"] = ramp_gravity(rig, p.drop_gravity_m_s2, p.gravity_m_s2, p.gravity_ramp_steps,
                                 progress)
    b = sim.balls
    ids = rig.stone_balls()
    sim.delete_balls(ids[b.pos[ids, 1] + b.rad[ids] > p.height_m])
    remove_debris(rig, p.min_fragment_balls)
    deposition_conditions(rig, p, mu, on=False)
    wall_friction(rig, mu)
    sim.scale_bond_strength(1.0 / p.drop_bond_factor)
    ids = rig.stone_balls()
    top = float((b.pos[ids, 1] + b.rad[ids]).max())
    w2, wide = 0.5 * p.width_m, 0.6 * p.width_m
    lay.top = sim.add_wall([(w2 + wide, top), (-w2 - wide, top)], material_id=PLATEN).tolist()
    if lay.left_groups:
        place_membrane(rig)
    sim.set_damping(p.damping)
    sim.run(p.relax_steps)
    st["relax"] = p.relax_steps
    lay.stage_end["relax"] = {"steps": p.relax_steps, "force_ratio": stone_force_ratio(rig)}
    if progress is not None:
        progress(p.relax_steps)
    return rig
