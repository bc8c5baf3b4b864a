"""Biaxial-rig parameters: the ``rig: biaxial:`` section of the config (``assembly``: the
specimen; ``loading``: consolidation and cycling), flat as the rig code reads them
(``params.width_m``). SI units unless the key names one."""
from dataclasses import dataclass, field
from typing import ClassVar

from ..deposition import DepositionParams

KPA = 1.0e3


@dataclass
class BiaxialParams(DepositionParams):
    RIG: ClassVar[str] = "biaxial"
    # specimen (assembly)
    width_m: float = 0.30              # 2D slice of the 300 mm x 600 mm triaxial cylinder
    height_m: float = 0.60
    membrane_friction: float = 0.0     # side walls stand for the membrane: frictionless
    membrane_segments: int = 1         # 1: rigid side walls; n > 1: a membrane of n segments a side
    relax_steps: int = 5000
    # loading
    confining_pressure_kPa: float = 30.0
    deviator_min_kPa: float = 15.0
    deviator_max_kPa: float = 230.0
    servo_gain_m_s_per_kPa: float = 2.0e-4
    servo_velocity_m_s: float = 0.01
    servo_integral_steps: int = 5000
    consolidation_window_steps: int = 5000
    consolidation_tolerance: float = 0.02
    consolidation_max_windows: int = 200
    consolidation_platen_velocity_m_s: float = 0.05   # top servo's limit while consolidating
    consolidation_windows_in_a_row: int = 3           # consolidated: this many windows in a row
    consolidation_strain_rate_max_1_s: float = 2.0e-3  # ... with the specimen at rest
    mode: str = "quasi_static"         # or "real_time": true masses, sinusoidal q at f
    frequency_Hz: float = 20.0
    sine_servo_time_waves: float = 2.0      # the sinusoid's servo: time constant C / gain in t_w
    sine_velocity_min_m_s: float = 0.05     # its speed limit: this, or 2 pi f C dq if more
    sine_feed_forward: bool = True          # servo: plus -C dq/dt, C measured per branch,
                                            # and bounds adapted cycle by cycle
    load_control: str = "applied_force"     # from the first loading on, the platen's
                                            # sinusoid and the sides' p: loads on bodies,
                                            # the platen of ... ("servo": PI servos)
    platen_mass_ratio: float = 0.01         # ... this mass / the specimen's balls' mass
                                            # (the sides: the platen's mass per area)
    quasi_static_inertial_number: float = 1.0e-3   # quasi-static f: the inertial number ...
    quasi_static_lag: float = 0.1                   # ... and the stress's lag / (q_max - q_min)
    first_loading_inertial_number: float = 1.5e-5  # cycle 0, the profile (both modes): the
                                       # platen's speed, of this inertial number at p ...
    braking_speed_ratio: float = 0.1   # ... down to this fraction of it at each bound ...
    braking_fraction: float = 0.25     # ... over the last 25 % of the range
    realtime_added_inertia_max: float = 0.0     # real time: density scaling adds at most this
    failure_axial_strain: float = 0.15   # a stress-controlled specimen beyond this has failed
    softening_strain: float = 0.02       # ... or once q fell past its peak over this strain (peak.py)
    control_every: int = 10
    loading_dt_factor: float = 2.0
    checkpoint_every: int = 50
    timeseries_every: int = 10
    vtk_cycles: list = field(default_factory=lambda: [0, -1])
    max_cycle_steps: int = 5000000

    @property
    def axial_bounds_Pa(self):
        """sigma_1's cycle bounds (p + q_min, p + q_max) [Pa]."""
        p = self.confining_pressure_kPa * KPA
        return p + self.deviator_min_kPa * KPA, p + self.deviator_max_kPa * KPA

    @property
    def deviator_range_Pa(self):
        """q_max - q_min [Pa]."""
        return (self.deviator_max_kPa - self.deviator_min_kPa) * KPA

    def inert_keys(self):
        """Quasi-static: the test's frequency. The sinusoid starts at cycle 0's trough at
        the bounds' frequency, set from the compliance of the first loading branch (always
        measured: it moves the stress from p to p + q_max), so f never acts
        (tests/scenario/test_modifiers.py runs a case at two f: the same bytes)."""
        return ("frequency_Hz",) if self.mode == "quasi_static" else ()

    def first_cycle_inert_keys(self):
        """What cycle 0 does not read: the test's frequency (the first loading runs at
        first_loading_inertial_number in either mode; the sinusoid starts at its end).
        A run at the end of cycle 0 goes on under another f (BiaxialRun.continue_under)."""
        return ("frequency_Hz",)

    def take_conditions(self, c):
        """A measured test's loading conditions (``measured.importer.load_conditions``):
        p, the q bounds, f."""
        self.confining_pressure_kPa = c["confining_pressure_kPa"]
        self.deviator_max_kPa = c["deviator_max_kPa"]
        if c.get("deviator_min_kPa") is not None:
            self.deviator_min_kPa = c["deviator_min_kPa"]
        if c.get("frequency_Hz") is not None:
            self.frequency_Hz = c["frequency_Hz"]
        if not self.deviator_min_kPa < self.deviator_max_kPa:
            raise ValueError(f"deviator {self.deviator_min_kPa:g}-{self.deviator_max_kPa:g} kPa: "
                             "the minimum must be below the maximum")
