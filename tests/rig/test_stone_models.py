"""The box rig with each stone model (ballaststudy.stones) on the same assembled case: the
rigid model sees the stones the bonded one does (fragments, the links that make the
stone solids), its loading run records every cycle and resumes bit for bit from a
checkpoint after a crash; the rig asks the model, whichever it is."""
import numpy as np
import pytest

from ballaststudy.metrics.void_ratio import void_ratio
from ballaststudy.rig.box import BoxRig
from ballaststudy.rig.loading import LoadingRun
from ballaststudy.rig.records import to_dataset
from ballaststudy.stones import STONE_MODELS

CYCLES = 2


def _rigid(path):
    rig = BoxRig.load(path)
    rig.use_stone_model("rigid")
    return rig


def _solids(rig):
    """Void ratio with the stones as solid (the links make each stone's solid)."""
    p, sim = rig.params, rig.sim
    frag = rig.fragments()
    labels = np.full(len(sim.balls), -1)
    labels[: len(frag)] = frag
    i, j, intact = rig.stones.topology(sim)
    return void_ratio(sim.balls.pos, sim.balls.rad, labels, int(frag.max()) + 1, i, j, intact,
                      -0.5 * p.width_m, 0.5 * p.width_m, 0.0, p.depth_m)["void_ratio"]


def test_the_rigid_model_sees_the_stones_the_bonded_model_does(assembled):
    bonded, rigid = BoxRig.load(assembled[0]), _rigid(assembled[0])
    assert bonded.stones is STONE_MODELS["bonded"] and rigid.stones is STONE_MODELS["rigid"]
    frag = bonded.fragments()
    assert np.array_equal(rigid.fragments(), frag)
    assert rigid.stones.breakable_units(rigid.sim) == int(frag.max()) + 1
    assert bonded.stones.breakable_units(bonded.sim) == int((bonded.sim.bonds.active == 1).sum())
    assert _solids(rigid) == pytest.approx(_solids(bonded), rel=1e-12)
    b = rigid.sim.balls
    stone = rigid.stone_balls()
    assert (b.clump[stone] >= 0).all() and not (rigid.sim.bonds.active == 1)[
        b.clump[rigid.sim.bonds.i] == b.clump[rigid.sim.bonds.j]].any()
    # the clumps' own timestep from the first step (not the bonded specimen's): larger
    assert rigid.sim.dt == pytest.approx(rigid.params.dt_safety * rigid.sim.critical_dt(), rel=1e-12)
    assert rigid.sim.dt > bonded.sim.dt


@pytest.fixture(scope="module")
def rigid_run(assembled, tmp_path_factory):
    ck = tmp_path_factory.mktemp("rigid") / "ck.npz"
    return LoadingRun(_rigid(assembled[0]), cycles=CYCLES, checkpoint=ck, checkpoint_every=1).run()


def test_a_rigid_loading_run_records_its_cycles_without_breakage(rigid_run):
    ds = to_dataset(rigid_run)
    assert ds.attrs["stone_model"] == "rigid" and ds.sizes["cycle"] == CYCLES
    assert np.all(ds["breakage_rate"].values == 0.0) and ds.sizes.get("breakage", 0) == 0
    assert np.all(ds["broken_mass_share"].values == 0.0)
    assert np.all(np.isfinite(ds["settlement"])) and np.all((ds["void_ratio"] > 0) & (ds["void_ratio"] < 1))
    assert len(np.unique(ds["n_fragments"].values)) == 1


def test_a_rigid_run_resumes_bitwise_after_a_crash(rigid_run, assembled, tmp_path):
    ck = tmp_path / "ck.npz"
    first = LoadingRun(_rigid(assembled[0]), cycles=CYCLES, checkpoint=ck, checkpoint_every=1)
    first.run(stop_after=1)
    first.advance(max_steps=200)     # progress after the checkpoint that the crash loses
    resumed = LoadingRun.from_checkpoint(ck)
    assert resumed.rig.layout.stone_model == "rigid"
    resumed.run()
    a, b = to_dataset(rigid_run), to_dataset(resumed)
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    assert np.array_equal(rigid_run.rig.sim.clumps.pos, resumed.rig.sim.clumps.pos)


def test_vtk_draws_a_rigid_stones_links_as_intact(rigid_run, tmp_path):
    from ballaststudy.rig.vtk import write_vtk
    rig = rigid_run.rig
    _, bonds, _ = write_vtk(rig, tmp_path, "end")
    text = bonds.read_text()
    state = text.split('Name="state"')[1].split(">", 1)[1].split("<", 1)[0].split()
    i, j, intact = rig.stones.topology(rig.sim)
    live = (rig.sim.balls.alive[i] == 1) & (rig.sim.balls.alive[j] == 1)
    assert len(state) == live.sum()
    assert sum(s == "0" for s in state) >= intact[live].sum() > 0


# weak stones (sigma0 far below the contact stresses of the box's loading) so that some
# split within two cycles: the record, the rate and the resume are what is tested here
SPLITTING = dict(sigma0=2e5, m=3.0, d0=0.04, seed=5, fines_diameter=0.0, every=50)


def _splitting_rig(path):
    """The assembled case with some flat joints broken before loading (as real assemblies
    leave them: 17 on box_test case 1), then made rigid stones that split: the run's
    records must be its splits, none of the joints' rows."""
    rig = BoxRig.load(path)
    rig.sim.scale_bond_strength(1e-6, bonds=np.arange(3))
    rig.sim.run(300)
    assert rig.sim.n_breakages > 0
    rig.use_stone_model("rigid", SPLITTING)
    return rig


@pytest.fixture(scope="module")
def splitting_run(assembled, tmp_path_factory):
    rig = _splitting_rig(assembled[0])
    ck = tmp_path_factory.mktemp("split") / "ck.npz"
    return LoadingRun(rig, cycles=CYCLES, checkpoint=ck, checkpoint_every=1).run(), rig


def test_rigid_stones_that_split_are_recorded_and_rated_per_stone(splitting_run):
    run, rig = splitting_run
    ds = to_dataset(run)
    log = rig.sim.split_log()
    stones = run.s.n_bonds0
    n = len(log["step"])
    assert n > 0 and stones == len(np.unique(run.stone_unit[run.stone_unit >= 0]))   # the pieces at the start
    assert ds["breakage_mode_code"].attrs["flag_meanings"] == "split"
    assert np.array_equal(ds["breakage_step"].values, log["step"])     # every split, nothing else
    assert (ds["breakage_mode_code"].values == 3).all()
    in_cycles = int((ds["breakage_cycle"].values >= 0).sum())
    assert ds["breakage_rate"].values[-1] == pytest.approx(
        int((log["step"] <= ds["cycle_end_step"].values[-1]).sum()) / stones, rel=1e-12)
    assert in_cycles <= n
    # every split made a new clump; the fragments are the pieces
    assert rig.fragments().max() + 1 == stones + n - int((log["fines"] > 0).sum())
    # the mass share outside each stone's largest piece, from the engine's clump masses
    # (pieces grouped by the stone their lowest ball was in when loading began)
    b, cl = rig.sim.balls, rig.sim.clumps
    unit = run.stone_units(len(b))
    largest, total = {}, 0.0
    for c in range(len(cl.mass)):
        peb = np.flatnonzero(b.clump == c)
        if not len(peb) or unit[peb.min()] < 0:
            continue                            # the plate
        total += cl.mass[c]
        if (b.alive[peb] == 1).any():           # not fines
            largest[unit[peb.min()]] = max(largest.get(unit[peb.min()], 0.0), cl.mass[c])
    share = 1.0 - sum(largest.values()) / total
    assert ds["broken_mass_share"].values[-1] == pytest.approx(share, rel=1e-9) and share > 0
    assert np.all(np.diff(ds["broken_mass_share"].values) >= 0)


def test_a_splitting_run_resumes_bitwise_after_a_crash(splitting_run, assembled, tmp_path):
    run, rig = splitting_run
    ck = tmp_path / "ck.npz"
    rig2 = _splitting_rig(assembled[0])
    first = LoadingRun(rig2, cycles=CYCLES, checkpoint=ck, checkpoint_every=1)
    first.run(stop_after=1)
    first.advance(max_steps=200)     # progress after the checkpoint that the crash loses
    resumed = LoadingRun.from_checkpoint(ck)
    resumed.run()
    a, b = to_dataset(run), to_dataset(resumed)
    for name in a.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=True), name
    for k, v in rig.sim.split_log().items():
        assert np.array_equal(resumed.rig.sim.split_log()[k], v), k


def test_a_checkpoint_keeps_its_run_state_as_utf8_and_reads_the_older_string(rigid_run, assembled, tmp_path):
    """The run state (its per-cycle rows grow with the cycles) is UTF-8 bytes, a quarter of
    the numpy string it was; a checkpoint holding that string resumes to the same state."""
    ck = tmp_path / "ck.npz"
    first = LoadingRun(_rigid(assembled[0]), cycles=CYCLES, checkpoint=ck, checkpoint_every=1)
    first.run(stop_after=1)
    first.advance(max_steps=200)
    with np.load(ck) as z:
        data = {k: z[k] for k in z.files}
    assert data["state"].dtype == np.uint8
    text = data["state"].tobytes().decode()
    older = tmp_path / "older.npz"
    np.savez(older, **{**data, "state": np.array(text)})
    assert np.array(text).nbytes == 4 * data["state"].nbytes
    a, b = LoadingRun.from_checkpoint(ck), LoadingRun.from_checkpoint(older)
    assert a.s == b.s and a.s.cycle == 1
