"""What the box assembly's settle stages see: mean speeds through "settle after the drop" and
"settle after tamping" of one case, per check.

    NUMBA_NUM_THREADS=1 python bench/assembly_settle_trace.py --config config/thesis.yaml \
        --library results/bpm/G_2-2.nc --case 0 [--rows 12]

The stages stop when the mean stone-ball speed falls below ``settle_speed_m_s`` or at
``settle_max_steps``. In the thesis-scale run (2026-11-28) 78 of the 120 settle stages of
box_test and group 2 ended at the limit (300,000 steps each, ~half of an assembly's steps).
This prints, every ~1/rows of each stage, the mean ball speed the stage tests, the mean and
largest rigid speed of the stones (mean of their balls' velocities) and the 90th percentile
of the ball speeds, to tell whether the pile is still moving as stones or only vibrating
within them. G_2-2 case 0 (dt 3.3e-7 s, drop gravity 1000 m/s^2, frictionless): the stones
themselves move at 0.07-0.38 m/s (mean) throughout both stages, the fastest at 0.3-4 m/s,
with no trend towards rest after 50,000 steps: the pile keeps rearranging; a limit or a
criterion scaled to the drop gravity (sqrt(g d) ~ 5 m/s) would cut those steps, but changes
the specimen: check it with bench/box_before_after.py first. box_test case 1 ends its drop
stage at the limit with 0.0479 m/s, the value its assembled.nc records (the trace follows
the run's own trajectory), its stones still at 0.04-0.35 m/s; its tamping stage rises from
0.02 to 0.06 m/s before it settles at 104,000 steps. Never a test.
"""
import argparse
import time

import numpy as np

from ballaststudy.config import load_config
from ballaststudy.rig import assembly, deposition
from ballaststudy.rig.kinds import params_from_config
from ballaststudy.rig.library import load_library
from ballaststudy.rig.params import case_seed


def traced_settle(trace):
    """deposition.settle's loop and stop rule, recording the speeds at every check."""
    def settle(specimen, params, stage, progress=None):
        p, sim = params, specimen.sim
        steps, speed = 0, np.inf
        while steps < p.settle_max_steps and speed >= p.settle_speed_m_s:
            sim.run(p.settle_check_every)
            steps += p.settle_check_every
            ids = specimen.stone_balls()
            v = sim.balls.vel[ids]
            ball = np.hypot(*v.T)
            speed = float(ball.mean())
            stone = sim.balls.stone[ids]
            n = np.bincount(stone)
            live = n > 0
            rigid = np.hypot(np.bincount(stone, v[:, 0])[live], np.bincount(stone, v[:, 1])[live]) / n[live]
            trace.append((stage, steps, speed, rigid.mean(), rigid.max(), np.percentile(ball, 90)))
        return steps
    return settle


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="config/thesis.yaml")
    ap.add_argument("--library", required=True, help="a BPM library (results/bpm/<database>.nc)")
    ap.add_argument("--case", type=int, default=0)
    ap.add_argument("--rows", type=int, default=12, help="rows printed per stage")
    args = ap.parse_args()
    cfg = load_config(args.config)
    params = params_from_config("box", cfg["rig"])
    lib = load_library(args.library)
    trace = []
    # drop() calls deposition.settle, the tamping stage assembly's imported name
    deposition.settle = assembly.settle = traced_settle(trace)
    t0 = time.time()
    rig = assembly.assemble(lib, params, case_seed(cfg["seed"], lib.database, args.case))
    print(f"database={lib.database} case={args.case} seconds={time.time() - t0:.1f} dt={rig.sim.dt:.3g} "
          f"settle_speed_m_s={params.settle_speed_m_s} settle_max_steps={params.settle_max_steps}")
    for stage in dict.fromkeys(t[0] for t in trace):
        rows = [t for t in trace if t[0] == stage]
        print(f"{stage}: {rows[-1][1]} steps")
        for t in rows[:: max(1, len(rows) // args.rows)] + rows[-1:]:
            print(f"  step={t[1]:7d} mean_ball_m_s={t[2]:.4f} mean_stone_m_s={t[3]:.4f} "
                  f"max_stone_m_s={t[4]:.4f} p90_ball_m_s={t[5]:.4f}")


if __name__ == "__main__":
    main()
