"""The monotonic strength test (rig.biaxial.strength): the peak read from a planted curve
(phi from sin phi = q / (2 sigma_3 + q), psi from sin psi = -r / (2 - r), r = d eps_v /
d eps_a) to round-off; the inertial-number rate; on a small specimen the platen advances
at that rate, the sides hold p while it dilates (applied as loads, or by servos), and the
envelope gathers the tests."""
import math
import re

import numpy as np
import pytest

from ballaststudy.cli import main
from ballaststudy.rig.biaxial import BiaxialParams, assemble_biaxial
from ballaststudy.rig.biaxial.strength import (_peak, inertial_strain_rate, run_strength,
                                               strength_dataset)
from ballaststudy.rig.library import load_library

from ..netcdf_documented import assert_documented

P = 30.0e3


def test_peak_of_a_planted_curve():
    ea = np.arange(0.0, 0.08, 1e-4)
    q = 200e3 * (ea / 0.03) * np.exp(1.0 - ea / 0.03)        # from 0, peak 200 kPa at 3 %
    r = -0.4                                                 # dilating at the peak
    ev = 0.002 + r * (ea - 0.03)
    q_peak, phi, e_peak, psi, reached, seated = _peak(ea, ev, q, np.full_like(ea, P))
    assert q_peak == pytest.approx(200e3, rel=1e-9) and e_peak == pytest.approx(0.03, abs=1e-9)
    assert phi == pytest.approx(math.degrees(math.asin(200e3 / (2 * P + 200e3))), rel=1e-9)
    assert psi == pytest.approx(math.degrees(math.asin(0.4 / 2.4)), rel=1e-6)
    assert reached and 0.0 < seated < 0.03
    rising = _peak(ea[:200], ev[:200], q[:200], np.full(200, P))
    assert not rising[4]                                     # no peak within the strain


def test_inertial_strain_rate():
    # I = gamma_dot d sqrt(rho / p): 1e-3 = gamma_dot 0.04 sqrt(2500 / 1e4) -> 0.05 / s
    assert inertial_strain_rate(1e-3, 0.04, 2500.0, 1.0e4) == pytest.approx(0.05, rel=1e-12)


def strength_test(library, load_control):
    params = BiaxialParams(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
                           fill_area_ratio=0.9, consolidation_window_steps=1000,
                           load_control=load_control)
    rig = assemble_biaxial(load_library(library), params, seed=7)
    return rig, run_strength(rig, P / 1e3, inertial_number=1e-3, axial_strain_max=0.02)


@pytest.fixture(scope="module")
def strength(small_library):
    return strength_test(small_library, "applied_force")


SERVO_LAGS = pytest.mark.xfail(strict=True, reason=(
    "since soft rock's strength carries F_str-co (2026-12-07) this 24-stone specimen's stones no "
    "longer break: it jams (q 1.37 MPa at p 30 kPa, phi 73 deg, no peak by 2.5 % strain) and the "
    "side servos, tuned on specimens that crushed, lag its widening by up to 17.5 %"))


@pytest.mark.parametrize("load_control, within", [("applied_force", 0.01),
                                                  pytest.param("servo", 0.15, marks=SERVO_LAGS)])
def test_compression_at_the_rate_with_p_held(strength, small_library, load_control, within):
    """The sides hold p while the specimen dilates: within 1 % as loads on bodies (p is
    applied: their inertia is all that strays), within 15 % with the side servos (they
    lag the widening: bench/strength_table.py's sigma_3 column) - which no longer holds
    on this specimen (SERVO_LAGS)."""
    rig, r = strength if load_control == "applied_force" else strength_test(small_library, load_control)
    assert r.stop.startswith("the specimen failed") or "axial strain" in r.stop
    # the platen's strain after the run's steps at the inertial rate (dt fixed: true masses)
    assert r.axial_strain[-1] == pytest.approx(r.strain_rate * r.steps * rig.sim.dt, rel=0.05)
    assert np.all(np.abs(r.confining - P) < within * P)
    assert r.q_peak > 0.5 * P and 0.0 < r.phi_peak_deg < 90.0
    # the inertial masses' density: the real one plus what density scaling adds
    real = float(np.median(rig.sim.balls.mass[rig.stone_balls()]
                           / (np.pi * rig.sim.balls.rad[rig.stone_balls()] ** 2)))
    assert r.stone_density == pytest.approx(real * (1.0 + rig.sim.added_inertia()), rel=0.05)


def test_envelope_gathers_the_tests(strength, tmp_path, capsys):
    _, r = strength
    paths = []
    for k, p in enumerate((30.0, 60.0, 30.0)):
        path = tmp_path / f"s{k}.nc"
        strength_dataset(r, p, {"case": (0, 0, 1)[k]}).to_netcdf(path)
        paths.append(path)
    out = tmp_path / "envelope.nc"
    assert main(["case", "envelope", *map(str, paths), "--out", str(out), "--quiet"]) == 0
    import xarray as xr
    with xr.open_dataset(out) as env:
        assert list(env["confining_pressure"].values) == [30e3, 60e3]
        assert env["q_peak"].shape == (2, 2) and np.isnan(env["q_peak"].values[1, 1])
        assert float(env["q_peak_mean"][0]) == pytest.approx(r.q_peak)
        assert env.attrs["Conventions"].startswith("CF") and env["phi_peak_deg"].attrs["units"] == "degree"
    assert main(["case", "envelope", str(paths[0]), str(paths[0]), "--out", str(out), "--quiet"]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "twice" in line, line
    bad = tmp_path / "bad.nc"
    xr.Dataset(attrs={"Conventions": "CF-1.8"}).to_netcdf(bad)
    assert main(["case", "envelope", str(bad), "--out", str(tmp_path / "e2.nc"), "--quiet"]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and f"{bad}: " in line and "expected a strength test" in line, line


def test_the_test_stops_on_the_peak_it_reports(small_library):
    """The softening check and the curve read q one way (peak.py): a test stopped past its
    peak names the peak the curve reports."""
    params = BiaxialParams(width_m=0.15, height_m=0.30, drop_max_steps=200000, relax_steps=2000,
                           fill_area_ratio=0.9, consolidation_window_steps=1000,
                           softening_strain=0.003)
    rig = assemble_biaxial(load_library(small_library), params, seed=7)
    r = run_strength(rig, P / 1e3, inertial_number=1e-3, axial_strain_max=0.02)
    m = re.search(r"q peaked at ([\d.]+) kPa \(axial strain ([\d.]+)\)", r.stop)
    assert m, r.stop
    assert r.peak_reached and float(m[1]) * 1e3 == pytest.approx(r.q_peak, rel=0.005)
    assert float(m[2]) == pytest.approx(r.axial_strain_at_peak, abs=2e-4)
    # stopped once 0.003 past the peak; the curve's last sample may lie up to one sample before
    sample = np.diff(r.axial_strain).max()
    assert 0.003 - sample <= r.axial_strain[-1] - r.axial_strain_at_peak < 0.006


def _strength_file(strength, p_kPa, case, path):
    """The strength fixture's test as `case strength` writes it, at p and case."""
    strength_dataset(strength[1], p_kPa, {"case": case, "specimen": "assembled.nc"}).to_netcdf(path)
    return path


def test_documented_netcdf_strength_case(strength, tmp_path):
    assert_documented(_strength_file(strength, P / 1e3, 0, tmp_path / "case0.nc"), "strength_case")


def test_documented_netcdf_strength_envelope(strength, tmp_path):
    tests = [_strength_file(strength, p, 0, tmp_path / f"p{p:g}.nc") for p in (30.0, 60.0)]
    out = tmp_path / "envelope.nc"
    assert main(["case", "envelope", *map(str, tests), "--out", str(out), "--quiet"]) == 0
    assert_documented(out, "strength_envelope")
