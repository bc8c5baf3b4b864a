"""How fast a biaxial specimen may be cycled and still be quasi-static. Quasi-static cycles
are the real-time sinusoid (the platen's stress servo plus its feed-forward) at a frequency
below two physical bounds, with density scaling (only the states at rest matter):

- The inertial number I = gamma_dot d sqrt(rho / p) (GDR MiDi 2004; da Cruz et al. 2005,
  Phys. Rev. E 72) of the sheared specimen. In the mu(I) law mu = mu_s + (mu_2 - mu_s) /
  (I_0 / I + 1) (I_0 ~ 0.3) the stress ratio at I = 1e-3 exceeds its rate-independent
  value by ~0.3 % of (mu_2 - mu_s), inside any specimen's scatter: below it, loading
  faster costs nothing physical. d is the stones' median equivalent diameter, rho their
  density (the inertial masses the engine steps with, density scaling included), p the
  confining pressure (the smallest principal stress: the bound is tightest there),
  gamma_dot the axial strain rate, at its largest in a sinusoid pi f C (q_max - q_min) / H
  (C = -dH/dsigma_1 the platen's compliance over a branch).
- The stress wave: the axial stress reaches the far platen a travel time t_w = H / c =
  sqrt(rho_b C H) later (c = sqrt(E / rho_b) the bar wave speed of the branch's modulus E =
  H / C, rho_b the specimen's bulk density), so while the stress changes at a rate r the
  specimen's stress differs along its height by about r t_w. The sinusoid's largest rate
  is pi f (q_max - q_min); keeping r t_w below a fraction ``lag`` of q_max - q_min bounds
  f. At the reversals the rate is zero and so is the lag: the bounds are reached by the
  whole specimen.

Cycle 0, the first loading (the bound-to-bound profile at a constant platen speed) and the
strength test take their strain rate from an inertial number alone; the first loading's is
far below the sinusoid's (first_loading_inertial_number, 1.5e-5): a virgin loading
rearranges the stones, and how far depends on the rate down to I ~ 2e-5. Measured on three
0.15 x 0.30 m box_test specimens (bench/first_loading_rate.py, p = 30 kPa, q 15-80 kPa):
the axial strain after cycle 0 at I = 1.6e-3, 1.6e-4, 4.9e-5, 1.6e-5, 4.9e-6 was 2e-5,
0.0084, 0.0035, 0.0026, 0.0026 on one seed, (0.0040, 0.0046, 0.0047 on another); a 1 %
change of the speed changed it by < 2e-5 (a rate effect, not chaos). On one 0.30 x 0.60 m
specimen: 0.0235, 0.0319, 0.0287 after cycle 0 at I = 1.6e-4, 1.5e-5, 5e-6, 0.0240, 0.0323,
0.0323 after three cycles, but the volumetric strain then 0.014, 0.016, -0.001: not shown
converged at full size."""
import numpy as np


def stone_size_and_density(rig, inertial=False):
    """(median equivalent diameter sqrt(4 A / pi) of the stones, their mean density) [m,
    kg/m^3]: A a stone's ball area, the density the engine's masses have (mass / area t;
    ``inertial``: the inertial masses, density scaling included)."""
    b, ids = rig.sim.balls, rig.stone_balls()
    area = np.pi * b.rad[ids] ** 2
    per_stone = np.bincount(b.stone[ids], weights=area)
    d = float(np.median(np.sqrt(4.0 * per_stone[per_stone > 0] / np.pi)))
    mass = rig.sim.inertial_masses()[ids] if inertial else b.mass[ids]
    rho = float(mass.sum() / (area.sum() * rig.sim.thickness))
    return d, rho


def bulk_density(rig):
    """The specimen's bulk density [kg/m^3]: the stones' inertial mass over the volume W H t
    between the walls."""
    ids = rig.stone_balls()
    return float(rig.sim.inertial_masses()[ids].sum() / (rig.width() * rig.height() * rig.sim.thickness))


def inertial_strain_rate(inertial_number, d, rho, p):
    """gamma_dot = I / (d sqrt(rho / p)) [1/s] (p [Pa])."""
    return inertial_number / (d * np.sqrt(rho / p))


def profile_speed(rig, inertial_number, p):
    """The platen speed [m/s] of a constant-speed compression at inertial number I at p
    [Pa]: gamma_dot(I) H, d and rho the stones' (inertial masses)."""
    d, rho = stone_size_and_density(rig, inertial=True)
    return float(inertial_strain_rate(inertial_number, d, rho, p) * rig.height())


def travel_time(rho_b, compliance, height):
    """t_w = H / c = sqrt(rho_b C H) [s] (C [m/Pa])."""
    return float(np.sqrt(rho_b * compliance * height))


def quasi_static_frequency(rig, compliance, p, dq, inertial_number, lag):
    """The largest sinusoid frequency [Hz] within both bounds: the inertial number at p
    [Pa] (pi f C dq / H <= gamma_dot(I)) and the stress wave (pi f dq t_w <= lag dq), for
    the deviator range dq [Pa] and the platen's compliance C [m/Pa]."""
    d, rho = stone_size_and_density(rig, inertial=True)
    h = rig.height()
    f_inertial = inertial_strain_rate(inertial_number, d, rho, p) * h / (np.pi * compliance * dq)
    f_wave = lag / (np.pi * travel_time(bulk_density(rig), compliance, h))
    return float(min(f_inertial, f_wave))
