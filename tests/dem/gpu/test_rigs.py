"""Rigs' cyclic runs driven together on the GPU batch (rig/batched.py) under numba's CUDA
simulator: each run's own code, its records as on the CPU."""
import copy
import types

import numpy as np
import pytest

from ballaststudy.dem.control import Control
from ballaststudy.dem.gpu import BatchError
from ballaststudy.rig.batched import run_batched
from ballaststudy.rig.biaxial import BiaxialParams, BiaxialRig, BiaxialRun, assemble_biaxial
from ballaststudy.rig.cyclic import CyclicRun
from ballaststudy.rig.library import load_library
from ballaststudy.stones import STONE_MODELS

from ...biaxial_fast import FAST_LOADING
from .beds import assert_same_motion


class WallCycles(CyclicRun):
    """A cyclic run of the smallest kind: a bed's right wall pushed between two reactions
    (the sensors: its reaction and its position)."""
    CHANNELS = {"force": 0, "x": 1}
    CYCLE_FIELDS = {"x_peak": ("m", "right wall at the peak")}
    dt_factor = None

    def on_cycle_start(self):
        if self.dt_factor and self.s.cycle == 0:      # as the biaxial rig's real time
            self.rig.sim.set_density_scaling(self.dt_factor * self.rig.sim.dt)

    def cycle_row(self):
        return {"x_peak": float(self.samples["x"][self.s.peak_sample])}

    def behaviours(self):
        return {"force_max": float(self.cycle_samples("force").max())}


def wall_cycles(sim, cycles, dt_factor=None):
    """``cycles`` cycles of the right wall between its reaction + 0.2 N and + 1 N; with
    ``dt_factor`` the run switches density scaling on at its first trough, as the
    biaxial rig does for real-time loading."""
    right = [len(sim.walls) - 1]
    f0 = float(sim.walls.force[right[0], 0])
    ctl = Control(every=1, capacity=64)
    ctl.cyclic(ctl.wall_force(right, 0), ctl.walls(right, 0), lo=f0 + 0.2, hi=f0 + 1.0,
               v_min=5e-4, v_max=5e-3, brake=0.3)
    ctl.wall_position(right, 0)
    ctl.build()
    rig = types.SimpleNamespace(sim=sim, stones=STONE_MODELS["bonded"],
                                fragments=lambda: STONE_MODELS["bonded"].fragments(sim, len(sim.balls)))
    run = WallCycles(rig, cycles, ctl)
    run.dt_factor = dt_factor
    return run


def test_runs_driven_together_keep_their_records(beds):
    """Two runs of three cycles (one switches density scaling on at its first trough)
    driven as one batch: every cycle's records, the samples and the motion as each run
    has them alone on the CPU."""
    sims = [copy.deepcopy(beds[0]), copy.deepcopy(beds[1])]
    alone = [wall_cycles(copy.deepcopy(s), 3, f) for s, f in zip(sims, (None, 4.0))]
    engine_runs = []
    for r in alone:
        run = r.rig.sim.run
        r.rig.sim.run = lambda *a, run=run, **k: (engine_runs.append(1), run(*a, **k))[1]
        r.run()
    clock = {}
    together = run_batched([wall_cycles(s, 3, f) for s, f in zip(sims, (None, 4.0))],
                           check_every=4, clock=clock)
    assert sims[1].dt == 4.0 * beds[1].dt
    assert clock["export_n"] == len(engine_runs)      # one halt per engine run
    assert 1 <= clock["advance_n"] <= len(engine_runs)
    assert all(clock[k] >= 0.0 for k in ("hosts", "start", "advance", "export"))
    for a, t in zip(alone, together):
        assert t.s.phase == "done" and t.s.cycle == 3
        assert t.samples["step"] == a.samples["step"]
        assert t.samples["cycle"] == a.samples["cycle"]
        assert np.allclose(t.samples["force"], a.samples["force"], rtol=1e-9)
        assert np.allclose(t.cyc["x_peak"], a.cyc["x_peak"], rtol=0, atol=1e-15)
        assert [r["force_max"] for r in t.s.rows] == pytest.approx(
            [r["force_max"] for r in a.s.rows], rel=1e-9)
        assert_same_motion(a.rig.sim, t.rig.sim)
        assert "run" not in vars(t.rig.sim)            # the engine's own run again


def test_a_run_the_batch_cannot_hold_is_refused_and_the_others_finish(beds):
    """A run that asks for an engine run with a callback fails, naming its case; the other
    run finishes all its cycles."""
    runs = [wall_cycles(copy.deepcopy(s), 2) for s in beds[:2]]

    def job(run):
        if run is runs[1]:
            run.rig.sim.run(10, callback=lambda s: False)
        run.run()

    with pytest.raises(BatchError, match="case 1: BatchError: case 1: a run with a callback"):
        run_batched(runs, job, check_every=4)
    assert runs[0].s.phase == "done"


def test_the_biaxial_rig_consolidates_on_the_batch_as_on_the_cpu(small_library, tmp_path):
    """The biaxial rig itself (flat-jointed stones, the servos of its consolidation on the
    platens and sides, density scaling), two specimens at p = 30 and 60 kPa: three engine
    runs of its consolidation (4 steps each) on the batch as on the CPU within round-off."""
    params = BiaxialParams(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
                           fill_area_ratio=0.9, **FAST_LOADING)
    assemble_biaxial(load_library(small_library), params, seed=7).save(tmp_path / "a.nc")

    def runs():
        out = []
        for p in (30.0, 60.0):
            rig = BiaxialRig.load(tmp_path / "a.nc")
            rig.params.confining_pressure_kPa = p
            out.append(BiaxialRun(rig, cycles=1))
        return out

    def job(run):
        for _ in range(3):
            run.advance(max_steps=4)

    cpu = runs()
    for r in cpu:
        job(r)
    gpu = run_batched(runs(), job, check_every=4)
    for c, g in zip(cpu, gpu):
        assert c.rig.sim.step == g.rig.sim.step and c.rig.sim.time == g.rig.sim.time
        assert np.abs(c.rig.sim.walls.vel).max() > 0.0           # the platens move
        assert_same_motion(c.rig.sim, g.rig.sim)
        assert np.abs(c.rig.sim.walls.seg - g.rig.sim.walls.seg).max() < 1e-15
        assert np.allclose(c.rig.sim.walls.vel, g.rig.sim.walls.vel, rtol=1e-9, atol=1e-15)
        assert np.allclose(c.control.arrays.val, g.control.arrays.val, rtol=1e-9)
