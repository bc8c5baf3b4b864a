"""Scalar run parameters packed in one float64 array (``prm``) for the numba kernels.

Kernels never read config or globals except these integer index constants, which numba
freezes at compile time. The Python side (``Simulation``) fills the array.
"""
import numpy as np

DT = 0            # timestep [s]
GX = 1            # gravity x [m/s^2]
GY = 2            # gravity y [m/s^2]
ALPHA = 3         # default local damping of balls added later (per-ball array in state)
ALPHA_CLUMP = 4   # default for clumps added later
THICK = 5         # out-of-plane thickness t [m]
SKIN = 6          # Verlet skin [m]
VMAX = 8          # runaway guard: max speed [m/s]
XMIN = 9          # domain (ball centres must stay inside) [m]
YMIN = 10
XMAX = 11
YMAX = 12
AUTO_DT = 18      # 1 = recompute dt = f*dt_crit at every neighbour rebuild
DT_SAFETY = 19    # f [-]
DSCALE = 20       # 1 = density scaling (inertial masses set so that dt_crit = dt/f)
TIME = 21         # simulated time [s]
WALL_TRAVEL = 23  # wall endpoint travel since the last neighbour build [m]
SHIFT_X = 24      # common displacement estimate c (mean of the previous step) [m]
SHIFT_Y = 25
# rigid stones that split (crushing.py); CRUSH_EVERY = 0: none split
CRUSH_EVERY = 26  # stone stresses checked at steps that are multiples of this [-]
CRUSH_SIGMA0 = 27  # Weibull characteristic strength of a stone of diameter CRUSH_D0 [Pa]
CRUSH_M = 28      # Weibull modulus [-]                       (these two: material 0, hard)
CRUSH_D0 = 29     # reference diameter [m]
CRUSH_SEED = 30   # seed of the strength streams [-]
CRUSH_FINES = 31  # pieces of an equivalent diameter below this are fines (removed) [m]
CRUSH_SIGMA0_SOFT = 32  # the same two for stones of material 1 (soft: Table 4.2's weaker
CRUSH_M_SOFT = 33       # joints make weaker stones, a law of their own)
CRUSH_CRITERION = 34    # the stress compared with the strength: 0 F_max / (d t), 1 deviator
NPRM = 35

# energy accumulator slots (``energy_acc`` array)
E_DASHPOT = 0     # work dissipated by contact dashpots [J]
E_FRICTION = 1    # work dissipated by Coulomb slip (contacts and broken FJ elements) [J]
E_LOCAL = 2       # work dissipated by local damping [J]
E_BREAKAGE = 3    # strain energy released when flat-joint elements break [J]
E_WALLS = 4       # work done on balls by moving walls / velocity-controlled bodies [J]
E_ROLLING = 5     # work dissipated by rolling resistance (plastic rolling and its dashpot) [J]
NENERGY = 6

# run-status codes returned by the stepping kernel
OK = 0
NEED_PAIR_CAPACITY = 1
NEED_WALL_CAPACITY = 2
NAN_FOUND = 3
RUNAWAY = 4
LEFT_DOMAIN = 5
CONTROL_EVENT = 6     # a controller (control.py) asks the caller to react
STONES_OVERLOADED = 7  # a rigid stone reached its strength: the caller splits it
STATUS_TEXT = {NAN_FOUND: "NaN/Inf in ball state", RUNAWAY: "runaway velocity",
               LEFT_DOMAIN: "ball left the domain"}


def new_params():
    p = np.zeros(NPRM)
    p[THICK] = 1.0
    p[VMAX] = 1.0e3
    p[DT_SAFETY] = 0.8
    p[AUTO_DT] = 1.0
    return p
