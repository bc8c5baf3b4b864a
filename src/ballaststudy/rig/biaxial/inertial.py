"""The inertial number of a sheared granular specimen, I = gamma_dot d sqrt(rho / p)
(GDR MiDi 2004; da Cruz et al. 2005, Phys. Rev. E 72): how far its deformation is from
quasi-static. In the mu(I) law mu = mu_s + (mu_2 - mu_s) / (I_0 / I + 1) (I_0 ~ 0.3) the
stress ratio at I = 1e-3 exceeds its rate-independent value by ~0.3 % of (mu_2 - mu_s),
inside any specimen's scatter: below it, loading faster costs nothing physical. d is the
stones' median equivalent diameter, rho their density (the real masses: density scaling
adds inertia to the smallest balls only, ~2 % of the mass), gamma_dot taken as the axial
strain rate. The biaxial rig's loading rates (strength test, quasi-static cycles) come
from here."""
import numpy as np


def stone_size_and_density(rig):
    """(median equivalent diameter sqrt(4 A / pi) of the stones, their mean density) [m,
    kg/m^3]: A a stone's ball area, the density the engine's masses have (mass / area t)."""
    b, ids = rig.sim.balls, rig.stone_balls()
    area = np.pi * b.rad[ids] ** 2
    per_stone = np.bincount(b.stone[ids], weights=area)
    d = float(np.median(np.sqrt(4.0 * per_stone[per_stone > 0] / np.pi)))
    rho = float(b.mass[ids].sum() / (area.sum() * rig.sim.thickness))
    return d, rho


def inertial_strain_rate(inertial_number, d, rho, p):
    """gamma_dot = I / (d sqrt(rho / p)) [1/s] (p [Pa])."""
    return inertial_number / (d * np.sqrt(rho / p))
