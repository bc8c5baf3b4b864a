"""The monotonic strength test of a biaxial specimen: isotropic consolidation to p (as the
cyclic test), then the top platen compresses the specimen at a constant axial strain rate
while the sides keep p, through the peak of the deviator q = sigma_1 - sigma_3 (a
strain-controlled drained biaxial compression test). Results: the curves q, axial and
volumetric strain, and at the peak q_peak, the friction angle phi_peak
(sin phi = (sigma_1 - sigma_3) / (sigma_1 + sigma_3)) and the dilatancy angle psi
(2D: sin psi = -r / (2 - r), r = d eps_v / d eps_a, compression positive).

The rate is the strain rate of inertial number ``inertial_number`` (config
strength.inertial_number, 1.5e-5; inertial.py), with the quasi-static mode's density scaling
(loading_dt_factor: inertia added to the smallest balls only). phi_peak depends on it: on
three 0.15 x 0.30 m box_test specimens (bench/strength_table.py, seeds 1-3, mu 0.7, p
applied to the sides) the mean phi_peak at I = 1e-3 / 1e-4 / 1.5e-5 was 55.5 / 49.8 /
46.5 deg at p = 30 kPa and 49.8 / 43.4 / 42.0 at p = 60 kPa, not converged: between the
last two rates seeds moved -6.1, -6.3, +2.5 deg at 30 kPa and +1.8, -6.5, +0.6 at 60
(with side servos, which let sigma_3 stray up to 19 %, 30 kPa looked converged). 1.5e-5,
the first loading's bound (first_loading_inertial_number), is the slowest rate measured.
q is read as its mean over peak.WINDOW_STRAIN of axial strain, the measure on which the
test also stops past its peak (BiaxialRun.check_stalled)."""
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from ...metrics.strain import specimen_strains
from .inertial import inertial_strain_rate, stone_size_and_density
from .loading import BiaxialRun
from .params import KPA
from .peak import WINDOW_STRAIN, window_mean

DILATANCY_STRAIN = 0.005     # d eps_v / d eps_a: a line over +- this around the peak


@dataclass
class StrengthResult:
    axial_strain: np.ndarray
    volumetric_strain: np.ndarray
    deviator: np.ndarray               # q = sigma_1 - sigma_3 [Pa], smoothed
    confining: np.ndarray              # sigma_3 [Pa], smoothed
    q_peak: float
    phi_peak_deg: float
    axial_strain_at_peak: float
    dilatancy_angle_deg: float         # at the peak
    peak_reached: bool                 # False: q still rose at the end (no peak within the strain)
    seating_strain: float              # axial strain before q first reached q_peak / 10
    strain_rate: float
    inertial_number: float
    stone_diameter: float
    stone_density: float
    steps: int
    stop: str


def run_strength(rig, p_kPa, inertial_number, axial_strain_max=0.10, side_gain=1.0e-3,
                 side_integral_steps=500, progress=None):
    """Consolidate ``rig`` (assembled, not loaded) to p, then compress at the inertial
    number's strain rate until axial_strain_max or past the peak by the rig's
    softening_strain, the sides loaded with p (load_control applied_force: bodies of the
    rig's boundary mass per area; sigma_3 stays within 0.1 % of p where the servos let it
    stray 19 %, bench/strength_table.py) or (servo) the side servos at ``side_gain`` [m/s
    per kPa], integral time ``side_integral_steps`` and up to twice the platen's speed: a
    dilating specimen widens at up to about half of it, and they must follow or sigma_3
    swings. Measured at p = 30
    kPa: with the cyclic servos' 2e-4 m/s/kPa, 0.01 m/s, 5000 steps sigma_3 swung 22-78 kPa
    (0.15 x 0.30 m box_test specimen); 1e-3 and 5000 steps gave 28-33 kPa there and 25-39
    kPa on the tests' synthetic specimen, 1e-3 and 500 steps 29-32 kPa on the latter (5e-3:
    28-49, it overshoots). Returns a StrengthResult."""
    prm = rig.params
    prm.confining_pressure_kPa = p_kPa
    prm.mode = "quasi_static"
    prm.failure_axial_strain = axial_strain_max
    prm.max_cycle_steps = np.iinfo(np.int64).max // 2
    run = BiaxialRun(rig, cycles=1)
    while run.s.phase == "consolidation":
        run.advance()
    d, rho = stone_size_and_density(rig, inertial=True)
    rate = inertial_strain_rate(inertial_number, d, rho, p_kPa * KPA)
    v = rate * run.s.height0
    for k in run.ids.sides:
        sign = np.sign(run.control.get(k, "gain"))
        run.control.set(k, gain=sign * side_gain, v_max=max(prm.servo_velocity_m_s, 2.0 * v),
                        integral_steps=side_integral_steps)
    # the bound-to-bound profile at one speed towards a bound it never meets: constant v
    run.control.set(run.ids.sine, active=False)
    run.control.set(run.ids.profile, lo=0.0, hi=1e30, v_min=v, v_max=v, direction=-1, active=True)
    k0, s0 = len(run.samples["step"]), rig.sim.step
    while run.s.phase != "done":
        run.advance()
        run._rescale()      # sigma = F / (L t) on the current W and H: no event rescales here
        if progress is not None:
            progress(run.strains()[0])
    curve = _curve(run, k0)
    return StrengthResult(*curve, *_peak(*curve), strain_rate=rate, inertial_number=inertial_number,
                          stone_diameter=d, stone_density=rho, steps=rig.sim.step - s0,
                          stop=run.s.failure)


def _curve(run, k0):
    """(axial strain, volumetric strain, q, sigma_3) from the loading's samples, one point
    per 1e-4 of axial strain, q and sigma_3 as their means over WINDOW_STRAIN of it
    (peak.window_mean)."""
    s, S = run.s, {k: np.asarray(v[k0:]) for k, v in run.samples.items()}
    h, w = S["platen_y"] - run.rig.bottom_y(), S["right_x"] - S["left_x"]
    ea, ev = specimen_strains(h, w, s.height0, s.width0)
    order = np.maximum.accumulate(ea)
    keep = np.unique(np.searchsorted(order, np.arange(0.0, order[-1], 1e-4)))
    sig3 = 0.5 * (S["left_stress"] + S["right_stress"])
    q = S["axial_stress"] - sig3
    return (ea[keep], ev[keep], window_mean(order, q, order[keep]),
            window_mean(order, sig3, order[keep]))


def _peak(ea, ev, q, sig3):
    """(q_peak, phi_peak [deg], axial strain there, psi there [deg], peak reached)."""
    k = int(np.argmax(q))
    s1 = sig3[k] + q[k]
    phi = np.degrees(np.arcsin(q[k] / (s1 + sig3[k])))
    near = np.abs(ea - ea[k]) <= DILATANCY_STRAIN
    r = np.polyfit(ea[near], ev[near], 1)[0] if near.sum() >= 3 else np.nan
    psi = np.degrees(np.arcsin(np.clip(-r / (2.0 - r), -1.0, 1.0)))
    seated = ea[np.argmax(q >= 0.1 * q[k])]
    return (float(q[k]), float(phi), float(ea[k]), float(psi),
            bool(k < q.size - 1 and ea[-1] - ea[k] > WINDOW_STRAIN), float(seated))


CURVES = {   # variable: (result field, units, long name)
    "axial_strain": ("axial_strain", "1", "axial strain 1 - H/H0 since the end of consolidation, "
                     "compression positive"),
    "volumetric_strain": ("volumetric_strain", "1", "volumetric (2D: area) strain 1 - W H / (W0 H0), "
                          "compression positive"),
    "deviator_stress": ("deviator", "Pa", f"deviator q = sigma_1 - sigma_3, mean over {WINDOW_STRAIN:g} "
                        "of axial strain"),
    "confining_stress": ("confining", "Pa", f"sigma_3 (mean of the sides), mean over {WINDOW_STRAIN:g} "
                         "of axial strain")}
PEAK_UNITS = {"q_peak": "Pa", "phi_peak_deg": "degree", "axial_strain_at_peak": "1",
              "dilatancy_angle_deg": "degree", "peak_reached": "1", "seating_strain": "1",
              "strain_rate": "1/s", "inertial_number": "1", "stone_diameter": "m",
              "stone_density": "kg/m^3", "steps": "1", "stop": ""}


def strength_dataset(result, p_kPa, attrs=None):
    """The test's curves on a ``point`` axis and its peak values as attributes (name_units
    the units of each)."""
    d = asdict(result)
    ds = xr.Dataset({name: ("point", np.asarray(d[field], float), {"units": u, "long_name": n})
                     for name, (field, u, n) in CURVES.items()})
    ds.attrs = {"Conventions": "CF-1.8", "title": "biaxial strength test: strain-controlled "
                "compression through the peak at p (ballaststudy.rig.biaxial.strength)",
                "confining_pressure_Pa": p_kPa * KPA,
                "stress_convention": "2D stresses: force per boundary length per thickness t; "
                "compression positive", **(attrs or {})}
    for k, units in PEAK_UNITS.items():
        v = d[k]
        ds.attrs[k] = int(v) if isinstance(v, bool) else v
        ds.attrs[f"{k}_units"] = units
    return ds


ENVELOPE = {"q_peak": ("Pa", "peak deviator q_peak"),
            "phi_peak_deg": ("degree", "secant peak friction angle: sin phi = q / (2 sigma_3 + q)"),
            "dilatancy_angle_deg": ("degree", "dilatancy angle at the peak"),
            "axial_strain_at_peak": ("1", "axial strain at the peak"),
            "seating_strain": ("1", "axial strain before q first reached q_peak / 10"),
            "peak_reached": ("1", "1: q fell after its peak within the test's strain; 0: still rising")}


def strength_envelope(datasets):
    """The specimens' strength envelope from strength tests (datasets with a
    ``confining_pressure_Pa`` and a ``case`` attribute): each peak value on (p, case), and
    its mean and standard deviation over the cases at each p."""
    ps = sorted({float(d.attrs["confining_pressure_Pa"]) for d in datasets})
    cases = sorted({int(d.attrs["case"]) for d in datasets})
    out = xr.Dataset(coords={"confining_pressure": ("confining_pressure", np.array(ps),
                                                    {"units": "Pa", "long_name": "confining pressure p"}),
                             "case": ("case", np.array(cases), {"units": "1", "long_name": "specimen case"})})
    seen = [(float(d.attrs["confining_pressure_Pa"]), int(d.attrs["case"])) for d in datasets]
    if len(set(seen)) < len(seen):
        raise ValueError(f"a test of the same p and case given twice: {sorted(seen)}")
    for name, (units, long_name) in ENVELOPE.items():
        a = np.full((len(ps), len(cases)), np.nan)
        for d in datasets:
            a[ps.index(float(d.attrs["confining_pressure_Pa"])), cases.index(int(d.attrs["case"]))] = d.attrs[name]
        out[name] = (("confining_pressure", "case"), a, {"units": units, "long_name": long_name})
        if name != "peak_reached":
            for stat, f in (("mean", np.nanmean), ("std", np.nanstd)):
                out[f"{name}_{stat}"] = ("confining_pressure", f(a, axis=1),
                                         {"units": units, "long_name": f"{long_name}, {stat} over the cases"})
    out.attrs = {"Conventions": "CF-1.8", "title": "strength envelope of a specimen set: monotonic "
                 "biaxial tests at the confining pressures of the configured measured tests",
                 **{k: v for k, v in datasets[0].attrs.items()
                    if k in ("inertial_number", "stress_convention", "specimens")}}
    return out
