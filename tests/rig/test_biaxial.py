"""The cyclic biaxial rig on a small specimen (coarse synthetic library): isotropic
consolidation reaches p on every side; a static deviator hold balances the platen and side
forces against (p + q) W t and p H t and the bottom platen against top + weight; cycles
reach their bounds with the confinement held and are recorded; resume after a kill gives
the same bytes; unbreakable stones under repeated q shake down."""
import numpy as np
import pytest
import xarray as xr

from ballaststudy.rig.biaxial import (AXIAL, KPA, BiaxialParams, BiaxialRig, BiaxialRun,
                                      assemble_biaxial, write_biaxial_outputs)
from ballaststudy.rig.library import load_library

from ..biaxial_fast import FAST_LOADING
from ..netcdf_documented import assert_documented

SMALL = dict(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
             fill_area_ratio=0.9, checkpoint_every=1, deviator_min_kPa=10.0,
             deviator_max_kPa=60.0, **FAST_LOADING)


@pytest.fixture(scope="module")
def specimen(small_library, tmp_path_factory):
    rig = assemble_biaxial(load_library(small_library), BiaxialParams(**SMALL), seed=7)
    path = tmp_path_factory.mktemp("biaxial") / "assembled.nc"
    rig.save(path)
    return path


def test_specimen(specimen):
    rig = BiaxialRig.load(specimen)
    ids = rig.stone_balls()
    b = rig.sim.balls
    assert rig.layout.bonds_installed == rig.layout.bonds_library
    assert rig.width() == pytest.approx(0.15)
    assert 0.25 < rig.height() <= 0.30 + 1e-9
    assert np.all(b.pos[ids, 1] + b.rad[ids] <= rig.height() + 1e-3)
    assert rig.sim.n_breakages == 0
    bd = rig.sim.bonds                        # the cuts' bonds are out of the bond loops
    assert np.all(b.alive[bd.i] & b.alive[bd.j])


def test_consolidation_reaches_p(specimen):
    rig = BiaxialRig.load(specimen)
    run = BiaxialRun(rig, cycles=1)
    while run.s.phase == "consolidation":
        run.advance()
    p = rig.params.confining_pressure_kPa * KPA
    np.testing.assert_allclose(run.s.window_means[-1], p, rtol=0.02)
    assert np.all(np.abs(np.array(rig.stresses()) - p) < 0.15 * p), "a wall lost contact"
    assert run.s.height0 == pytest.approx(rig.height())


def test_consolidated_only_at_rest_and_in_a_row(specimen):
    """The last windows of the consolidation: consolidation_windows_in_a_row of them within
    the tolerance; a window counts only with the axial strain rate since the last one below
    consolidation_strain_rate_max_1_s (rates 0.75 and 1.5 x the limit: a factor of two in
    the rate's formula fails this)."""
    rig = BiaxialRig.load(specimen)
    run = BiaxialRun(rig, cycles=1)
    while run.s.phase == "consolidation":
        run.advance()
    p, n = rig.params, rig.params.consolidation_windows_in_a_row
    np.testing.assert_allclose(run.s.window_means[-n:], p.confining_pressure_kPa * KPA,
                               rtol=p.consolidation_tolerance)
    h, t, limit = rig.height(), rig.sim.time, p.consolidation_strain_rate_max_1_s
    for factor, at_rest in ((0.75, True), (1.5, False)):
        run.s.window_height, run.s.window_time = h * (1.0 + factor * limit * 0.01), t - 0.01
        assert run._at_rest() is at_rest, factor


def test_first_loading_at_its_inertial_number(specimen):
    """Cycle 0's platen, before it brakes, compresses the specimen at the strain rate of
    first_loading_inertial_number: I = (dH/dt / H) d sqrt(rho / p), d the stones' median
    equivalent diameter and rho their density (inertial masses), computed here from the
    balls. Within 2 %: a factor of two, or sqrt(rho) for rho, misses by more."""
    rig = BiaxialRig.load(specimen)
    run = BiaxialRun(rig, cycles=1)
    while run.s.phase == "consolidation":
        run.advance()
    b, ids = rig.sim.balls, rig.stone_balls()
    area = np.bincount(b.stone[ids], weights=np.pi * b.rad[ids] ** 2)
    d = np.median(np.sqrt(4.0 * area[area > 0] / np.pi))
    rho = (1.0 / b.minv[ids]).sum() / (np.pi * (b.rad[ids] ** 2).sum() * rig.sim.thickness)
    p = rig.params.confining_pressure_kPa * KPA
    h0, t0 = rig.height(), rig.sim.time
    rig.sim.run(300, control=run.control)           # far from p + q_max: no braking yet
    assert run.control.reading(AXIAL) < p + 0.5 * rig.params.deviator_max_kPa * KPA
    rate = (h0 - rig.height()) / (h0 * (rig.sim.time - t0))
    inertial = rate * d * np.sqrt(rho / p)
    assert inertial == pytest.approx(rig.params.first_loading_inertial_number, rel=0.02)


def test_static_deviator_hold_balances_forces(specimen):
    """Means over the window after the hold (forces from the walls, W and H from their
    positions): each side p H t within 2 %, bottom platen = top + weight of the stones
    within 2 %, top platen (p + q) W t within 3 %: the hold ends when the servo's window
    mean is within 2 % (consolidation_tolerance), and in the next window the specimen
    still creeps under the new deviator (measured: servo 1.001, next window 1.026, five
    windows later 1.013; 1.009 with another rounding of the flat-joint kernel)."""
    rig = BiaxialRig.load(specimen)
    run = BiaxialRun(rig, cycles=1)
    q = 40.0
    run.hold(q)
    sim, lay, t = rig.sim, rig.layout, rig.sim.thickness
    top, bottom, left, right = [], [], [], []
    for _ in range(100):
        sim.run(10, control=run.control)
        f = sim.wall_force()
        top.append(f[lay.top, 1].sum())
        bottom.append(-f[lay.bottom, 1].sum())
        left.append(-f[lay.left, 0].sum())
        right.append(f[lay.right, 0].sum())
    p = rig.params.confining_pressure_kPa * KPA
    w, h = rig.width(), rig.height()
    assert np.mean(top) == pytest.approx((p + q * KPA) * w * t, rel=0.03)
    assert np.mean(left) == pytest.approx(p * h * t, rel=0.02)
    assert np.mean(right) == pytest.approx(p * h * t, rel=0.02)
    weight = sim.balls.mass[rig.stone_balls()].sum() * rig.params.gravity_m_s2
    assert np.mean(bottom) == pytest.approx(np.mean(top) + weight, rel=0.02)


CYCLES = 3


@pytest.fixture(scope="module")
def cycled(specimen, tmp_path_factory):
    ck = tmp_path_factory.mktemp("cyc") / "metrics.checkpoint.npz"
    return BiaxialRun(BiaxialRig.load(specimen), cycles=CYCLES, checkpoint=ck).run()


def test_cycles_reach_bounds_with_confinement_held(cycled, tmp_path):
    p = cycled.rig.params
    c = cycled.cyc
    assert len(c["cycle_end_step"]) == CYCLES
    hi = (p.confining_pressure_kPa + p.deviator_max_kPa) * KPA
    lo = (p.confining_pressure_kPa + p.deviator_min_kPa) * KPA
    top, bottom = np.array(c["axial_stress_max"]), np.array(c["axial_stress_min"])
    # cycle 0: the profile, to each bound (it reverses on a sample beyond it: the load
    # cell's 0.5 ms mean lies near it)
    assert abs(top[0] - hi) < 0.02 * (hi - lo) and abs(bottom[0] - lo) < 0.02 * (hi - lo)
    # then the sinusoid (its servo, feed-forward and adapted bounds), the last cycle closest
    assert np.all(np.abs(top - hi) < 0.1 * (hi - lo)) and np.all(np.abs(bottom - lo) < 0.1 * (hi - lo))
    assert abs(top[-1] - hi) < 0.02 * (hi - lo) and abs(bottom[-1] - lo) < 0.02 * (hi - lo)
    np.testing.assert_allclose(c["confining_stress_mean"], p.confining_pressure_kPa * KPA, rtol=0.05)
    ea = [r["axial_strain"] for r in cycled.s.rows]
    assert np.all(np.isfinite(ea)) and ea[-1] > 0          # compressed under the deviator
    # packing of the specimen rectangle: the balls' porosity = 1 - their disk area / W H
    # (bonded disks overlap a little: within 0.02), stones as solid leave less void
    rig, last = cycled.rig, cycled.s.rows[-1]
    ids = rig.stone_balls()
    disks = np.pi * (rig.sim.balls.rad[ids] ** 2).sum() / (rig.width() * rig.height())
    assert last["void_ratio_balls"] == pytest.approx(1 - disks, abs=0.02)
    assert 0 < last["void_ratio"] < last["void_ratio_balls"]
    stones_left = np.unique(rig.sim.balls.stone[ids]).size      # the cut deleted some
    assert last["mean_coordination"] >= 1.0 and last["n_fragments"] >= stones_left
    ds = write_biaxial_outputs(cycled, tmp_path / "metrics.nc")
    with xr.open_dataset(tmp_path / "metrics.nc") as back:
        assert back.sizes["cycle"] == CYCLES
        for name in ("axial_strain", "volumetric_strain", "breakage_rate", "axial_stress_max",
                     "sample_axial_stress"):
            assert back[name].attrs["units"] and back[name].attrs["long_name"], name
        assert "per thickness" in back.attrs["stress_convention"]
    assert (tmp_path / "case.png").stat().st_size > 1000
    assert ds.attrs["Conventions"].startswith("CF")


def test_resume_is_identical(cycled, specimen, tmp_path):
    ck = tmp_path / "ck.npz"
    first = BiaxialRun(BiaxialRig.load(specimen), cycles=CYCLES, checkpoint=ck)
    first.run(stop_after=1)
    first.advance(max_steps=200)          # progress the kill loses
    assert first.s.cycle == 1
    resumed = BiaxialRun.from_checkpoint(ck).run()
    for k in cycled.cyc:
        assert np.array_equal(cycled.cyc[k], resumed.cyc[k], equal_nan=True), k
    assert cycled.s.rows == resumed.s.rows
    assert np.array_equal(cycled.rig.sim.balls.pos, resumed.rig.sim.balls.pos)


def test_unbreakable_stones_shake_down(specimen):
    """Stones that cannot break (bond strengths x 1e6) under 50 cycles of q: the permanent
    axial strain accumulated over cycles 1-10 is positive and at least five times that over
    cycles 40-49 (ten-cycle sums: single increments are within the platen's noise and may
    even be negative early on, as the packing rearranges). Measured: 14x and >100x with two
    rounding variants of the flat-joint kernel; a packing that does not shake down gives ~1x."""
    rig = BiaxialRig.load(specimen)
    rig.sim.scale_bond_strength(1e6)
    run = BiaxialRun(rig, cycles=50).run()
    assert rig.sim.n_breakages == 0
    ea = np.array([r["axial_strain"] for r in run.s.rows])
    early = ea[10] - ea[0]
    late = ea[49] - ea[39]
    assert early > 0 and abs(late) * 5 <= early, (early, late)


def test_case_cli_runs_the_biaxial_rig(small_library, tmp_path):
    """`case assemble --rig biaxial` then `case run`: the rig kind travels with the
    assembled file; metrics.nc, figures and VTK written."""
    import json
    from pathlib import Path

    import yaml

    from ballaststudy.cli import main
    root = Path(__file__).resolve().parents[2]
    cfg = yaml.safe_load((root / "config" / "config.yaml").read_text())
    cfg["databases_file"] = str(root / cfg["databases_file"])
    stages = cfg["rig"]["biaxial"]
    for k, v in SMALL.items():
        stage = "assembly" if k in stages["assembly"] else "loading"
        stages[stage][k] = v
    config = tmp_path / "config.yaml"
    config.write_text(yaml.safe_dump(cfg))
    asm, out = tmp_path / "assembled.nc", tmp_path / "metrics.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "biaxial",
                 "--out", str(asm), "--config", str(config), "--quiet"]) == 0
    conditions = tmp_path / "test.yaml"          # a measured test's conditions
    conditions.write_text(yaml.safe_dump(dict(
        source="planted", rig="triaxial", confining_pressure_kPa=20.0, deviator_max_kPa=50.0,
        frequency_Hz=10.0, curves=[dict(file="a.dat", quantity="axial_strain", units="1",
                                        sign="compression_positive")])))
    assert main(["case", "run", str(asm), "--cycles", "2", "--out", str(out), "--config",
                 str(config), "--conditions", str(conditions), "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.sizes["cycle"] == 2 and "axial_strain" in ds
        prm = json.loads(ds.attrs["rig_params_json"])
        assert (prm["confining_pressure_kPa"], prm["deviator_max_kPa"]) == (20.0, 50.0)
        assert prm["frequency_Hz"] == 10.0 and prm["mode"] == "quasi_static"
        # the first loading to p + q_max (the profile reverses on a sample at the bound; the
        # record, the load cell's 0.5 ms mean, lies up to 2 % below where a pulse ended it)
        assert ds["axial_stress_max"].values[0] >= 0.98 * 70e3
    assert (tmp_path / "behaviours.png").is_file() and any((tmp_path / "vtk").iterdir())


@pytest.mark.parametrize("control, within", [("applied_force", 0.02), ("servo", 0.05)])
def test_real_time_mode_follows_the_frequency(specimen, control, within):
    """Real-time mode at f = 20 Hz: cycle 0 (N = 1) is the bound-to-bound profile, as in
    quasi-static mode; from its trough on the real masses but for the density scaling of
    the smallest balls within realtime_added_inertia_max (1 % here, 0 by default: the run
    ends at 0.5-1.5 % with the contacts it has then, and at a dt above the automatic one);
    each later cycle lasts 1/f within 1 % of simulated time, the measured axial stress
    oscillates at f within 1 % (the best least-squares sinusoid over a grid of 0.8-1.2 f in
    0.1 % steps: single peaks are too noisy to time; cycles 1-3), and every cycle reaches
    both bounds: within 2 % of the range with the load applied to the platen (its mass
    scaled with the balls'), within 5 % with the servo and the feed-forward of the
    measured compliance (bench/realtime_bounds.py measures 0.2-1.6 % on the small box_test
    specimen at 5-60 Hz; a sign or factor-of-two error in the feed-forward misses by tens
    of %)."""
    rig = BiaxialRig.load(specimen)
    p = rig.params
    p.mode, p.frequency_Hz, p.realtime_added_inertia_max = "real_time", 20.0, 0.01
    p.load_control = control
    run = BiaxialRun(rig, cycles=4).run()
    assert 0.005 < rig.sim.added_inertia() < 0.015
    assert rig.sim.dt > 1.05 * rig.sim.scaled_timestep(0.0)      # the automatic dt
    periods = np.array(run.cyc["cycle_steps"][1:]) * rig.sim.dt
    np.testing.assert_allclose(periods, 1.0 / p.frequency_Hz, rtol=0.01)
    assert np.isnan(run.cyc["loading_frequency"][0])
    np.testing.assert_allclose(run.cyc["loading_frequency"][1:], p.frequency_Hz)
    keep = np.array(run.samples["cycle"]) >= 1
    t = np.array(run.samples["step"])[keep] * rig.sim.dt
    sig = np.array(run.samples["axial_stress"])[keep]

    def residual(f):
        a = np.column_stack([np.ones_like(t), np.cos(2 * np.pi * f * t), np.sin(2 * np.pi * f * t)])
        return np.linalg.lstsq(a, sig, rcond=None)[1][0]

    grid = p.frequency_Hz * np.arange(0.8, 1.2, 0.001)
    best = grid[np.argmin([residual(f) for f in grid])]
    assert best == pytest.approx(p.frequency_Hz, rel=0.01)
    lo = (p.confining_pressure_kPa + p.deviator_min_kPa) * KPA
    hi = (p.confining_pressure_kPa + p.deviator_max_kPa) * KPA
    top = (np.array(run.cyc["axial_stress_max"]) - lo) / (hi - lo)      # fractions of the range
    bottom = (np.array(run.cyc["axial_stress_min"]) - lo) / (hi - lo)
    assert np.all(np.abs(top - 1.0) < within) and np.all(np.abs(bottom) < within), (top, bottom)


@pytest.mark.parametrize("strain, soft, why", [
    (0.01, 1.0, "axial strain 0.0"), (1.0, 0.005, "and fell below it over a further")])
def test_a_deviator_beyond_the_strength_fails_the_specimen(specimen, tmp_path, strain, soft, why):
    """q_max far above what the specimen can carry: as in a stress-controlled test it fails
    (axial strain at the failure strain, or past its peak by the softening strain; never
    max_cycle_steps in the first loading, which at a slow inertial number may take more);
    the run ends as a result with the reason, and metrics.nc records it."""
    rig = BiaxialRig.load(specimen)
    p = rig.params
    p.deviator_max_kPa, p.failure_axial_strain, p.softening_strain, p.max_cycle_steps = 5000.0, strain, soft, 1000
    run = BiaxialRun(rig, cycles=1).run()
    assert run.s.phase == "done" and run.s.cycle == 0
    assert run.s.failure.startswith("the specimen failed in the first loading: ") and why in run.s.failure
    if strain < 1:
        assert strain <= run.strains()[0] < 2 * strain
    if soft < 1:       # the strain after the peak, and sigma_1 below its peak
        assert soft <= run.strains()[0] - run.s.peak_strain < 2 * soft
        q = np.asarray(run.samples["axial_stress"]) - 0.5 * (np.asarray(run.samples["left_stress"])
                                                             + np.asarray(run.samples["right_stress"]))
        assert np.mean(q[-50:]) < run.s.peak_stress
    assert run.control.reading(AXIAL) < 0.5 * 5030.0 * KPA     # far below the bound it could not reach
    write_biaxial_outputs(run, tmp_path / "metrics.nc", figures=False)
    with xr.open_dataset(tmp_path / "metrics.nc") as ds:
        assert ds.attrs["failed"] == 1 and ds.attrs["failure"] == run.s.failure and ds.sizes["cycle"] == 0


def test_a_collapse_under_applied_loads_is_caught_within_the_watch(specimen):
    """Under applied loads the platen is a body whose speed has no bound: a sinusoid raised
    in cycle 1 far beyond the strength (3000 kPa) accelerates it into a collapsing
    specimen. The engine runs between failure checks are short enough that the run ends
    within a quarter of softening_strain past failure_axial_strain (watched at the sine's
    v_max instead, one run of the engine carried it 1.2 % of axial strain past it)."""
    rig = BiaxialRig.load(specimen)
    p = rig.params
    assert p.load_control == "applied_force"
    run = BiaxialRun(rig, cycles=4)
    while not (run.s.phase == "cyclic" and run.s.cycle >= 1):
        run.advance()
    p.deviator_max_kPa = 3000.0
    run.control.set(run.ids.sine, hi=p.axial_bounds_Pa[1])
    run.run()
    assert run.s.failure.startswith("the specimen failed in cycle 1: axial strain")
    past = run.strains()[0] - p.failure_axial_strain
    assert 0.0 <= past < 0.25 * p.softening_strain, past


def test_a_cycle_beyond_max_cycle_steps_fails_the_specimen(specimen):
    """A cycle of the sinusoid that does not end within max_cycle_steps ends the run as a
    failure in that cycle (after cycle 0, which the cap does not cut: it had 1000 steps)."""
    rig = BiaxialRig.load(specimen)
    rig.params.max_cycle_steps = 1000
    run = BiaxialRun(rig, cycles=3).run()
    assert run.s.phase == "done" and len(run.s.rows) == 1
    assert run.s.failure.startswith("the specimen failed in cycle 1: the cycle between") \
        and "did not end within max_cycle_steps 1000" in run.s.failure


# ------------------------------------------------------------------ flexible membrane
MEMBRANE = 6


@pytest.fixture(scope="module")
def membrane_specimen(small_library, tmp_path_factory):
    params = BiaxialParams(**SMALL, membrane_segments=MEMBRANE)
    rig = assemble_biaxial(load_library(small_library), params, seed=7)
    path = tmp_path_factory.mktemp("membrane") / "assembled.nc"
    rig.save(path)
    return path


def assert_membrane_spans_the_specimen(rig, atol=1e-12):
    """n segments a side, each 1/n of the height between the platens, end to end; the
    extensions reach beyond the platens from the end nodes (to round-off: the engine moves
    a wall's points about its centre every step; after a run, to what the platen moved in
    the last engine run: ``atol``)."""
    seg, lay = rig.sim.walls.seg, rig.layout
    bottom, top = seg[lay.bottom[0], 1], seg[lay.top[0], 1]
    nodes = np.linspace(bottom, top, MEMBRANE + 1)
    for side in ("left", "right"):
        groups = rig.side_groups(side)
        assert len(groups) == MEMBRANE
        for k, g in enumerate(groups):
            ys = np.sort(seg[g[0], [1, 3]])
            np.testing.assert_allclose(ys, nodes[k:k + 2], rtol=0, atol=atol)
            assert seg[g[0], 0] == seg[g[0], 2]          # vertical
            for ext in g[1:]:
                assert np.all(seg[ext, [0, 2]] == seg[g[0], 0])
                ye = np.sort(seg[ext, [1, 3]])
                assert (ye[1] - bottom if k == 0 else ye[0] - top) == pytest.approx(0, abs=atol)


def test_membrane_assembled(membrane_specimen):
    rig = BiaxialRig.load(membrane_specimen)
    assert rig.params.membrane_segments == MEMBRANE
    assert_membrane_spans_the_specimen(rig)
    assert rig.width() == pytest.approx(0.15)


def test_membrane_hold_balances_each_segment(membrane_specimen):
    """Static deviator hold with the membrane: each side p H t and the top (p + q) W t
    (W the mean width, area / H) within 2 %, as for rigid walls; and each segment, under its
    own servo, carries p L t (L = H / n) within 10 % (a segment meets few stones)."""
    rig = BiaxialRig.load(membrane_specimen)
    run = BiaxialRun(rig, cycles=1)
    q = 40.0
    run.hold(q)
    sim, lay, t = rig.sim, rig.layout, rig.sim.thickness
    groups = rig.side_groups("left") + rig.side_groups("right")
    top, sides, segs = [], [], []
    for _ in range(100):
        sim.run(10, control=run.control)
        f = sim.wall_force()
        top.append(f[lay.top, 1].sum())
        sides.append([-f[lay.left, 0].sum(), f[lay.right, 0].sum()])
        segs.append([abs(f[g, 0].sum()) for g in groups])
    p = rig.params.confining_pressure_kPa * KPA
    w, h = rig.width(), rig.height()
    assert np.mean(top) == pytest.approx((p + q * KPA) * w * t, rel=0.03)
    np.testing.assert_allclose(np.mean(sides, axis=0), p * h * t, rtol=0.02)
    np.testing.assert_allclose(np.mean(segs, axis=0), p * h / MEMBRANE * t, rtol=0.10)
    assert np.ptp(rig.side_x("left")) > 0 or np.ptp(rig.side_x("right")) > 0   # not a rigid wall


def test_membrane_follows_the_platens_and_resumes_identically(membrane_specimen, tmp_path):
    """Cycles with the membrane: it keeps spanning the specimen as the platen moves, no
    stone ball gets past it, sigma_3 is held within 5 %, and a run killed after a cycle
    resumes to the same bytes."""
    full = BiaxialRun(BiaxialRig.load(membrane_specimen), cycles=CYCLES,
                      checkpoint=tmp_path / "a.npz").run()
    rig, p = full.rig, full.rig.params
    assert_membrane_spans_the_specimen(rig, atol=1e-4)
    np.testing.assert_allclose(full.cyc["confining_stress_mean"], p.confining_pressure_kPa * KPA, rtol=0.05)
    ids = rig.stone_balls()
    x, r = rig.sim.balls.pos[ids, 0], rig.sim.balls.rad[ids]
    assert np.all(x - r > rig.side_x("left").min() - 1e-3) and np.all(x + r < rig.side_x("right").max() + 1e-3)
    assert np.all(np.array(full.cyc["width_max_at_end"]) >= np.array(full.cyc["width_at_end"]))
    ck = tmp_path / "b.npz"
    first = BiaxialRun(BiaxialRig.load(membrane_specimen), cycles=CYCLES, checkpoint=ck)
    first.run(stop_after=1)
    first.advance(max_steps=200)
    resumed = BiaxialRun.from_checkpoint(ck).run()
    for k in full.cyc:
        assert np.array_equal(full.cyc[k], resumed.cyc[k], equal_nan=True), k
    assert full.s.rows == resumed.s.rows
    assert np.array_equal(rig.sim.walls.seg, resumed.rig.sim.walls.seg)


def test_case_assemble_takes_the_specimen_size(small_library, tmp_path, capsys):
    """`case assemble --width-m/--height-m/--membrane-segments` (measured_sim's specimen):
    the specimen has that size and membrane; the options are refused for the box rig."""
    from ballaststudy.cli import main
    out = tmp_path / "assembled.nc"
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "biaxial",
                 "--width-m", "0.12", "--height-m", "0.24", "--membrane-segments", "3",
                 "--out", str(out), "--quiet"]) == 0
    rig = BiaxialRig.load(out)
    assert rig.width() == pytest.approx(0.12) and 0.2 < rig.height() <= 0.24 + 1e-9
    assert len(rig.side_groups("left")) == len(rig.side_groups("right")) == 3
    capsys.readouterr()
    assert main(["case", "assemble", str(small_library), "--case", "0", "--rig", "box",
                 "--width-m", "0.12", "--out", str(tmp_path / "box.nc"), "--quiet"]) == 2
    line = capsys.readouterr().err.strip()
    assert "rig.kind: box: --width-m is for a biaxial specimen" in line and "\n" not in line
    assert not (tmp_path / "box.nc").exists()


def test_documented_netcdf_assembled(assembled, specimen, membrane_specimen):
    """A box case (tests/rig/conftest.py), a biaxial specimen and one with a membrane."""
    for path in (assembled[0], specimen, membrane_specimen):
        assert_documented(path, "assembled")
