"""A small case end to end: assemble -> static -> cyclic -> per-cycle records; force
balance at the end of static loading; breakage counts = breakage records; resume from a
checkpoint gives identical per-cycle output; CLI and outputs."""
import numpy as np
import pytest
import xarray as xr

from ballaststudy.dem import Simulation
from ballaststudy.rig.box import BoxRig
from ballaststudy.rig.deposition import stone_force_ratio
from ballaststudy.rig.loading import CYCLE_FIELDS, LoadingRun
from ballaststudy.rig.records import to_dataset

CYCLES = 3


def test_assembly(assembled, small_params):
    path, rig = assembled
    lay = rig.layout
    b = rig.sim.balls
    ids = rig.stone_balls()
    w2 = 0.5 * small_params.width_m
    assert lay.bonds_installed == lay.bonds_library        # the library's bonds, all of them
    assert len(lay.bottom) == 20
    assert np.all(b.pos[ids, 0] - b.rad[ids] >= -w2 - 1e-3)
    assert np.all(b.pos[ids, 0] + b.rad[ids] <= w2 + 1e-3)
    assert np.all(b.pos[ids, 1] + b.rad[ids] <= small_params.depth_m + 1e-3)
    assert rig.sim.walls.seg[lay.left_low, 0] == pytest.approx(-w2, abs=1e-6)
    assert rig.sim.walls.seg[lay.right_low, 0] == pytest.approx(w2, abs=1e-6)
    assert rig.sim.n_breakages == 0, "bonds broke during the (strengthened) assembly"
    bd = rig.sim.bonds                        # the cuts' bonds are out of the bond loops
    assert np.all(b.alive[bd.i] & b.alive[bd.j])
    # frictionless while dropping and tamping, Table 4.2's friction everywhere afterwards
    assert small_params.assembly_friction == 0.0
    assert np.all(rig.sim.contact_coefficient("mu") == pytest.approx(0.7))
    again = BoxRig.load(path)                                # the file restores the state
    assert np.array_equal(again.sim.balls.pos, rig.sim.balls.pos)
    assert again.layout.plate == lay.plate and again.layout.loading == lay.loading
    assert again.layout.stages_at_limit == lay.stages_at_limit


def test_relaxed_until_at_rest(assembled, small_params):
    """Relaxation runs whole periods of relax_steps (after the gravity ramp) until the
    stones' force ratio is at most relax_force_ratio, and records where it stopped."""
    p, rig = small_params, assembled[1]
    end = rig.layout.stage_end["relax"]
    assert end["force_ratio"] <= p.relax_force_ratio
    assert end["force_ratio"] == pytest.approx(stone_force_ratio(rig), rel=1e-12)
    periods, rest = divmod(end["steps"] - p.gravity_ramp_steps, p.relax_steps)
    assert rest == 0 and periods >= 1 and end["steps"] == rig.layout.stage_steps["relax"]
    assert not any(x.startswith("relax") for x in rig.layout.stages_at_limit)


def test_stage_stopped_at_its_limit_is_recorded(small_library, small_params, assembled):
    """A settle cut off at settle_max_steps (500 steps: the pile has just landed at
    1000 m/s^2) is recorded with the speed it still had, a relaxation short of its force
    ratio with the ratio; the default stages are not."""
    from dataclasses import replace

    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.library import load_library
    p = replace(small_params, settle_max_steps=500, settle_check_every=500,
                relax_force_ratio=1e-9)          # at rest by no pile's measure: one period
    rig = assemble(load_library(small_library), p, seed=7)
    limits = rig.layout.stages_at_limit
    assert [x.split(":")[0] for x in limits] == ["settle after the drop", "settle after tamping",
                                                 "relax"]
    speed = float(limits[0].split("speed ")[1].split(" m/s")[0])
    assert speed >= p.settle_speed_m_s
    assert rig.layout.stage_end["relax"]["steps"] == p.gravity_ramp_steps + p.relax_steps
    assert not any(x.startswith("settle") for x in assembled[1].layout.stages_at_limit)


class _Pile:
    """Two one-ball stones for deposition.stone_force_ratio: the specimen interface."""
    def __init__(self, sim):
        self.sim = sim

    def stone_balls(self):
        return np.flatnonzero(self.sim.balls.stone >= 0)


def _pile(upper_y):
    """Stone 0 (r 1 cm) on the floor, stone 1 (r 0.5 cm) at ``upper_y``, resting on it when
    upper_y is its touching height; settled under damping (stone 1 falls freely above)."""
    sim = Simulation(gravity=(0.0, -9.81), damping=0.7)
    sim.add_wall([(-0.1, 0.0), (0.1, 0.0)])
    sim.add_balls([0.0], [0.01], [0.01], 2650.0, stone_id=0)
    sim.add_balls([0.0], [upper_y], [0.005], 2650.0, stone_id=1)
    sim.set_ball_velocity([1], hold=True)
    sim.run(20000)                           # stone 0 at rest (stone 1 held up there)
    sim.set_ball_velocity([1], hold=False)
    sim.run(1)
    return _Pile(sim)


def test_stone_force_ratio_is_pfcs_equilibrium_measure():
    """Mean |unbalanced force| / mean sum of force magnitudes over the stones (contacts from
    other stones and walls, weight): one stone at rest on the floor and one falling freely
    give (0 + m1 g) / (2 m0 g + m1 g) = m1 / (2 m0 + m1) (a wrong sign for a wall contact
    would count the floor's reaction twice, one for a stone-stone contact the other's
    weight); stacked at rest, 0."""
    m0, m1 = 0.01 ** 2, 0.005 ** 2
    falling = stone_force_ratio(_pile(0.1))
    assert falling == pytest.approx(m1 / (2 * m0 + m1), rel=1e-3)
    stacked = _pile(0.025 - 1e-6)
    stacked.sim.run(20000)
    assert stone_force_ratio(stacked) < 1e-3
    assert stone_force_ratio(_pile_free()) == pytest.approx(1.0)


def _pile_free():
    sim = Simulation(gravity=(0.0, -9.81), damping=0.0)
    sim.add_balls([0.0, 0.1], [0.5, 0.5], [0.01, 0.005], 2650.0, stone_id=0)
    sim.add_balls([0.3], [0.5], [0.01], 2650.0, stone_id=1)
    sim.run(1)
    return _Pile(sim)


def test_settling_stages_record_their_end(assembled):
    """Each settling stage records its steps, speed and the stones' force ratio; the relaxed
    specimen its force ratio when loading can start."""
    lay = assembled[1].layout
    assert set(lay.stage_end) == {"settle after the drop", "settle after tamping", "relax"}
    for stage in ("settle after the drop", "settle after tamping"):
        end = lay.stage_end[stage]
        assert end["steps"] > 0 and end["speed_m_s"] < 0.01 and 0 <= end["force_ratio"] < 1
    assert 0 <= lay.stage_end["relax"]["force_ratio"] < 1


def test_tamping_against_the_held_plate(small_library, small_params, assembled):
    """The thesis' order (4.2.2 c): cut at the depth and the plate held there before the
    tamping, the stones pushed up against it; the plate is not lowered onto the settled
    stones but released onto them in the relaxation. No stone ball reaches above its
    bottom under it; the specimen is another than the default order's."""
    from dataclasses import replace

    from ballaststudy.rig.assembly import assemble
    from ballaststudy.rig.library import load_library
    p = replace(small_params, tamping_against_plate=True)
    rig = assemble(load_library(small_library), p, seed=7)
    b, lay = rig.sim.balls, rig.layout
    bottom = (b.pos[lay.plate_balls, 1] - b.rad[lay.plate_balls]).min()
    assert lay.stage_steps["plate"] == 0 and bottom < p.depth_m
    ids = rig.stone_balls()
    under = np.abs(b.pos[ids, 0]) < 0.5 * p.plate_width_m
    assert (b.pos[ids[under], 1] - b.rad[ids[under]] < bottom).all()
    assert not lay.stages_at_limit
    default = assembled[1]
    assert len(ids) != len(default.stone_balls()) or not np.allclose(b.pos[ids], default.sim.balls.pos[ids])


def test_static_force_balance(assembled, small_params):
    """At the end of static loading (30 kN reached), the loading ball held still: loading
    force + weight of the stones and the plate = bottom + side-wall vertical forces + the
    local damping force on the stones and the plate, within 0.5 % of the static target
    (measured: within 0.11 % in the first 1000 steps after holding, 0.03 % from 2000 on).
    Side walls count with their sign: stones heaving at the walls are held down by
    friction. Local damping is a force from outside the packing: the held plate unloads as
    the coarse packing creeps (30.7 to 25.6 kN over 5000 steps), and on that moving packing
    it carried 1.2-2.4 % of the target (2026-11-29, AMD EPYC: this test failed there while
    it left damping out; an earlier machine's trajectory had stayed within 0.6 %). Why a
    settling window and the target as the scale: in the first ~2000 steps after holding the
    stones' deceleration is part of the balance, and as the load falls a ratio to the
    current load would measure the creep. The exact accounting of every external force,
    step by step, is test_static_loads_and_momentum_balance."""
    rig = BoxRig.load(assembled[0])
    run = LoadingRun(rig, cycles=1)
    while run.s.phase == "static":
        run.advance()
    target = 1e3 * small_params.static_loads_kN[-1]
    assert rig.loading_force() > 0.8 * target
    sim, lay = rig.sim, rig.layout
    sim.set_clump_velocity(lay.loading, vel=(0.0, 0.0), held=True)
    sim.run(3000)
    weight = rig.weight() - sim.clumps.mass[lay.loading] * rig.params.gravity_m_s2
    stones = rig.stone_balls()
    lhs, rhs = [], []
    for _ in range(50):
        sim.run(20)
        damping = (sim.local_damping_force(stones)[:, 1].sum()
                   + sim.local_damping_force(lay.plate, clumps=True)[0, 1])
        lhs.append(rig.loading_force() + weight - damping)
        rhs.append(rig.bottom_forces().sum() - rig.side_forces()[:, 1].sum())
    lhs, rhs = np.mean(lhs), np.mean(rhs)
    assert abs(lhs - rhs) / target < 0.005, f"plate load + weight - damping {lhs:.1f} N, walls {rhs:.1f} N"


STEPS = 300     # a short window: the held ball unloads as the packing creeps


def test_static_loads_and_momentum_balance(assembled, small_params):
    """The three static targets are met (10,000-step-style window means within 2.5 %); then,
    with the loading ball held and local damping off (it is a force on every body from
    outside), Newton's second law for stones + plate over 300 steps, step by step:
    mean(loading force + weight - forces on all walls) = change of momentum / time, within
    0.5 % of the load (measured: 0.01 %): the accounting of every external force, exact
    while the packing still moves."""
    rig = BoxRig.load(assembled[0])
    run = LoadingRun(rig, cycles=1)
    while run.s.phase == "static":
        run.advance()
    means = run.s.static_mean
    assert len(means) == 3
    for m, t in zip(means, small_params.static_loads_kN):
        assert abs(m - 1e3 * t) / (1e3 * t) < small_params.static_tolerance
    sim, lay = rig.sim, rig.layout
    b, c = sim.balls, sim.clumps
    sim.set_clump_velocity(lay.loading, vel=(0.0, 0.0), omega=0.0, held=True)
    sim.set_damping(alpha=0.0, clump_alpha=0.0)
    stones = rig.stone_balls()
    g = rig.params.gravity_m_s2
    weight = (b.mass[stones].sum() + c.mass[lay.plate]) * g

    def momentum():                       # inertial masses (density scaling raises them)
        return (b.vel[stones, 1] / b.minv[stones]).sum() + c.mass[lay.plate] * c.vel[lay.plate, 1]

    p0, t0, net, loads = momentum(), sim.time, [], []
    for _ in range(STEPS):
        sim.run(1)
        walls = sim.wall_force()[:, 1].sum()          # force of the balls on the walls, y
        loads.append(rig.loading_force())
        net.append(-loads[-1] - weight - walls)
    rate = (momentum() - p0) / (sim.time - t0)
    load = np.mean(loads) + weight
    assert load > 0.5 * 1e3 * small_params.static_loads_kN[-1]
    assert abs(np.mean(net) - rate) < 0.005 * load, \
        f"sum of forces {np.mean(net):.1f} N, momentum rate {rate:.1f} N, load {load:.1f} N"


@pytest.fixture(scope="module")
def full_run(assembled, tmp_path_factory):
    ck = tmp_path_factory.mktemp("full") / "ck.npz"
    run = LoadingRun(BoxRig.load(assembled[0]), cycles=CYCLES, checkpoint=ck, checkpoint_every=1)
    return run.run()


def test_cycles_recorded(full_run, small_params):
    ds = to_dataset(full_run)
    assert ds.sizes["cycle"] == CYCLES
    for k in CYCLE_FIELDS:
        assert "units" in ds[k].attrs and "long_name" in ds[k].attrs
    assert np.all(ds["force_max"] >= 1e3 * small_params.cyclic_max_kN)
    assert np.all(ds["force_min"] <= 1e3 * small_params.cyclic_min_kN * 1.0001 + 1e3)
    assert np.all(np.isfinite(ds["y_at_settlement_force"]))
    assert ds["bottom_force"].shape == (CYCLES, 20)
    assert ds["snapshot_x"].shape[0] == CYCLES
    assert np.all(ds["bottom_force"].sum("segment") > 1e3 * small_params.cyclic_max_kN * 0.5)
    # breakage counts = breakage records
    mode, cyc = ds["breakage_mode_code"].values, ds["breakage_cycle"].values
    for c in range(CYCLES):
        for name in ("elements_broken_tension", "broken_tension"):
            assert ds[name][c] == np.sum((mode == 1) & (cyc <= c)), name
        for name in ("elements_broken_shear", "broken_shear"):
            assert ds[name][c] == np.sum((mode == 2) & (cyc <= c)), name
    assert ds.attrs["metrics_package"].startswith("ballaststudy.metrics")
    for name in ("settlement", "breakage_rate", "fpa", "void_ratio", "ghost_particles"):
        assert name in ds and "units" in ds[name].attrs, name
    assert np.all(np.isfinite(ds["fpa"])) and np.all((ds["void_ratio"] > 0) & (ds["void_ratio"] < 1))


def test_resume_is_identical(full_run, assembled, tmp_path):
    ck = tmp_path / "ck.npz"
    first = LoadingRun(BoxRig.load(assembled[0]), cycles=CYCLES, checkpoint=ck, checkpoint_every=1)
    first.run(stop_after=1)
    first.advance(max_steps=200)     # progress after the checkpoint that the crash loses
    assert first.s.cycle == 1 and first.s.phase == "cyclic"
    resumed = LoadingRun.from_checkpoint(ck).run()
    a, b = to_dataset(full_run), to_dataset(resumed)
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    assert np.array_equal(full_run.rig.sim.balls.pos, resumed.rig.sim.balls.pos)


def test_outputs(full_run, tmp_path):
    from ballaststudy.rig.output import write_outputs
    from ballaststudy.rig.vtk import write_vtk
    ds = write_outputs(full_run, tmp_path / "metrics.nc")
    with xr.open_dataset(tmp_path / "metrics.nc") as back:
        assert back.sizes["cycle"] == CYCLES
        assert back["settlement"].attrs["long_name"]
    assert (tmp_path / "case.png").stat().st_size > 1000
    assert (tmp_path / "behaviours.png").stat().st_size > 1000
    paths = write_vtk(full_run.rig, tmp_path / "vtk", "end")
    text = paths[0].read_text()
    assert "<VTKFile" in text and 'Name="radius"' in text and 'Name="fragment"' in text
    assert ds.attrs["database"] == "tiny"


def test_density_scaling_option(assembled):
    rig = BoxRig.load(assembled[0])
    dt0 = rig.sim.dt
    rig.params.loading_dt_factor = 4.0
    run = LoadingRun(rig, cycles=1).run()
    assert rig.sim.dt == pytest.approx(4.0 * dt0)
    assert len(run.cyc["force_max"]) == 1 and run.cyc["force_max"][0] >= 45e3


def test_cyclic_speed_profile(assembled):
    """v_max until the force is within the braking fraction of the range from the bound
    approached, then linear down to v_min at the bound; direction = sign."""
    from ballaststudy.rig.loading import PROFILE
    rig = BoxRig.load(assembled[0])
    p = rig.params
    p.cyclic_v_max_m_s, p.cyclic_v_min_m_s, p.cyclic_braking_fraction = 0.1, 0.01, 0.25
    c = LoadingRun(rig, cycles=1).control
    c.set(PROFILE, direction=-1)                               # loading towards 45 kN
    band = 0.25 * 30e3
    assert c.velocity(PROFILE, 15e3) == pytest.approx(-0.1)
    assert c.velocity(PROFILE, 45e3 - band) == pytest.approx(-0.1)
    assert c.velocity(PROFILE, 45e3 - 0.5 * band) == pytest.approx(-0.055)
    assert c.velocity(PROFILE, 45e3) == pytest.approx(-0.01)
    c.set(PROFILE, direction=1)                                # unloading towards 15 kN
    assert c.velocity(PROFILE, 15e3 + 0.5 * band) == pytest.approx(0.055)
    assert c.velocity(PROFILE, 40e3) == pytest.approx(0.1)
