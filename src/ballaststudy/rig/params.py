"""Box-rig parameters: the ``rig: box:`` section of the config, by stage (``assembly``:
4.2.2, ``loading``: 4.2.3), with the thesis' numbers where it gives them (4.1, 4.2.2,
4.2.3) and defended choices where it does not (see config/thesis.yaml for the reason of
each; the defaults here are its values, checked by tests/workflow/test_param_defaults.py).
Units are SI unless the key names one. The rig code reads them flat (``params.width_m``);
the stage a key belongs to decides what reruns when it is edited (workflow/rules/cases.smk)."""
from dataclasses import dataclass, field
from typing import ClassVar

from ..seeds import job_seed
from .deposition import ROLLING_COEFFICIENTS, DepositionParams


@dataclass
class RigParams(DepositionParams):
    RIG: ClassVar[str] = "box"
    # container of the box test (thesis 4.1): inner width = cylinder diameter, height
    width_m: float = 0.34
    height_m: float = 0.22
    depth_m: float = 0.18              # ballast depth (4.2.2 c)
    bottom_segments: int = 20          # 4.2.2 d
    # not in the thesis
    tall_width_factor: float = 1.25    # tall container width / width during drop + tamping
    plate_width_m: float = 0.30
    plate_thickness_m: float = 0.02
    plate_density_kg_m3: float = 7850.0
    loading_ball_radius_m: float = 0.02
    loading_ball_density_kg_m3: float = 7850.0
    loading_contact_E_Pa: float = 5.0e8
    loading_contact_damping_ratio: float = 0.0
    tamping_velocity_m_s: float = 1.0
    tamping_gravity_m_s2: float = 1000.0
    tamping_pulses: int = 4
    tamping_steps: int = 20000
    tamping_against_plate: bool = False   # True: the thesis' order (4.2.2 c), see assembly.tamp
    wall_speed_m_s: float = 5.0
    plate_approach_gap_m: float = 2.0e-4
    plate_settle_velocity_m_s: float = 0.05
    relax_steps: int = 10000           # 4.2.2 d
    relax_force_ratio: float = 8.0e-3   # relaxed in periods of relax_steps until this (4.2.1)
    # loading (4.2.3)
    static_loads_kN: list = field(default_factory=lambda: [10.0, 20.0, 30.0])
    static_window_steps: int = 10000
    static_tolerance: float = 0.025
    static_max_windows: int = 40
    servo_velocity_m_s: float = 0.2
    servo_gain_m_s_per_kN: float = 0.05
    servo_integral_steps: int = 10000
    cyclic_min_kN: float = 15.0
    cyclic_max_kN: float = 45.0
    cyclic_v_max_m_s: float = 0.1
    cyclic_v_min_m_s: float = 0.01
    cyclic_braking_fraction: float = 0.25
    settlement_force_kN: float = 30.0
    cycles: int = 1000
    control_every: int = 10
    loading_dt_factor: float = 2.0
    checkpoint_every: int = 50
    snapshot_every: int = 10
    timeseries_every: int = 10
    vtk_cycles: list = field(default_factory=lambda: [0, -1])
    max_cycle_steps: int = 5000000

    def take_conditions(self, c):
        """A measured box test's load bounds (``measured.importer.load_conditions``), applied
        to the 2D rig as given, as the thesis applied the box test's loads. The static
        preloads and the settlement force keep their place relative to the cycle, as in
        4.2.3 (10, 20, 30 kN before cycles of 15-45 kN, settlement read at 30 kN): scaled so
        the last preload and the settlement force are the cycle's mean load. The frequency
        is not used: the box rig loads quasi-statically."""
        self.cyclic_max_kN = float(c["load_max_kN"])
        if c.get("load_min_kN") is not None:
            self.cyclic_min_kN = float(c["load_min_kN"])
        if not self.cyclic_min_kN < self.cyclic_max_kN:
            raise ValueError(f"cyclic load {self.cyclic_min_kN:g}-{self.cyclic_max_kN:g} kN: "
                             "the minimum must be below the maximum")
        mean = 0.5 * (self.cyclic_min_kN + self.cyclic_max_kN)
        ratio = mean / self.static_loads_kN[-1]
        self.static_loads_kN = [load * ratio for load in self.static_loads_kN]
        self.settlement_force_kN = mean

    def to_config(self):
        """The ``rig:`` dict these parameters come from (by stage; without rolling
        resistance its coefficients are no keys)."""
        d = self.to_dict()
        if self.rolling_resistance == "none":
            d = {k: v for k, v in d.items() if k not in ROLLING_COEFFICIENTS}
        return {"box": {"assembly": {k: v for k, v in d.items() if k not in LOADING_KEYS},
                        "loading": {k: v for k, v in d.items() if k in LOADING_KEYS}}}


# the keys of the loading stage (4.2.3); all others belong to the assembly (4.2.2)
LOADING_KEYS = frozenset((
    "static_loads_kN", "static_window_steps", "static_tolerance", "static_max_windows",
    "servo_velocity_m_s", "servo_gain_m_s_per_kN", "servo_integral_steps", "cyclic_min_kN",
    "cyclic_max_kN", "cyclic_v_max_m_s", "cyclic_v_min_m_s", "cyclic_braking_fraction",
    "settlement_force_kN", "cycles", "control_every", "loading_dt_factor", "checkpoint_every",
    "snapshot_every", "timeseries_every", "vtk_cycles", "max_cycle_steps"))


def case_seed(study_seed, database, case):
    """One seed per (database, case): config.job_seed of "<database>/case<k>"."""
    return job_seed(study_seed, f"{database}/case{int(case)}")
