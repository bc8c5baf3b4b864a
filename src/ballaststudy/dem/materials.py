"""Parameter dataclasses. Defaults are the calibrated values of the thesis, Table 4.2
(Wang 2018, ch. 4.3), hard rock unless stated.

F_str-co (strength and cohesion scaling factor) multiplies every tensile strength and
cohesion, hard and soft: Table 4.2 lists it as 3.5 for both rocks and 4.4 multiplies "each
tensile strength and cohesion" by it, though the table prints the factor in the hard
column's strengths only (sigma_c = F_str-co * 5.4e5 Pa, c = F_str-co * 60.0e5 Pa) and the
soft column's bare (3.0e5 Pa, 9.0e5 Pa): a factor of 3.5 for soft rock multiplies nothing
otherwise. ``FlatJointMaterial.scaled`` applies any further factor (the rig's bond
strengthening while dropping).
"""
from dataclasses import asdict, dataclass, replace

F_STR_CO = 3.5   # Table 4.2, hard and soft


@dataclass(frozen=True)
class ContactMaterial:
    """Linear contact model (LC) between stones, walls and the plate (Table 4.2 "LC").
    beta_n/beta_s: dashpot damping ratios (not in Table 4.2; PFC default 0).
    no_tension: the total normal force (spring + dashpot) may not pull (physics spec).
    ``coefficients()`` names them as the PFC-family sub-models do (law.py)."""
    E: float = 5.0e9          # effective modulus E_n* [Pa]
    kappa: float = 2.5        # normal-to-shear stiffness ratio [-]
    mu: float = 0.7           # friction coefficient [-]
    beta_n: float = 0.0
    beta_s: float = 0.0
    no_tension: bool = True
    mu_r: float = 0.0         # rolling friction (law with rolling="epsd") [-]
    kr_ratio: float = 1.0     # rolling stiffness k_r / (k_s R_r^2) [-] (PFC rrlinear: 1)
    eta_r: float = 0.0        # rolling dashpot ratio of critical [-]

    def coefficients(self):
        d = asdict(self)
        d["no_tension"] = float(self.no_tension)
        return d


@dataclass(frozen=True)
class FlatJointMaterial:
    """Flat-joint (FJ) bond parameters (Table 4.2 "FJ model")."""
    E: float = 2.5e9                  # effective modulus [Pa]
    kappa: float = 2.5                # normal-to-shear stiffness ratio [-]
    sigma_c: float = F_STR_CO * 5.4e5  # tensile strength [Pa]
    c: float = F_STR_CO * 60.0e5      # cohesion [Pa]
    phi_deg: float = 0.0              # friction angle [deg]
    mu: float = 0.5                   # residual friction of broken elements [-]
    lam: float = 1.0                  # radius multiplier lambda [-]
    gap_factor: float = 0.4           # installation gap g_i = gap_factor * D_small / 2

    @classmethod
    def hard(cls):
        return cls()

    @classmethod
    def soft(cls):
        return cls(E=4.0e9, kappa=2.0, sigma_c=F_STR_CO * 3.0e5, c=F_STR_CO * 9.0e5)

    def scaled(self, factor):
        """Same material with tensile strength and cohesion multiplied by ``factor``."""
        return replace(self, sigma_c=self.sigma_c * factor, c=self.c * factor)


# Table 4.2 densities [kg/m^3]
DENSITY_HARD = 2950.0
DENSITY_SOFT = 2800.0

# material ids of the balls (bpm: a stone's rock, the forms file's flag_meanings "hard soft");
# walls take ids above these (the rigs name theirs)
HARD, SOFT = 0, 1
STONE_MATERIALS = (HARD, SOFT)
MATERIAL_NAMES = ("hard", "soft")
