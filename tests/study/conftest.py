"""Synthetic inputs for the study stage: form databases built stone by stone from a grading
(so every coordinate has a hand value) and metrics.nc files with planted relations."""

import types

import numpy as np
import pytest
import xarray as xr

from ballaststudy.standards import GRADING_SIEVES_MM

UNITS = {"settlement": "m", "breakage_rate_tension": "1", "breakage_rate_shear": "1", "breakage_rate": "1",
         "fpa_left": "degree", "fpa_right": "degree", "fpa": "degree", "void_ratio": "1",
         "ghost_particles": "1", "mean_coordination": "1", "broken_tension": "1", "broken_shear": "1",
         "breakages_per_cycle": "1"}
PLANTED_ELEMENTS = 2000   # flat-joint elements per planted case: its broken counts are its rate x this

# Table 3-2 gradings (percent passing at 80 ... 8 mm) and Table 3-1 shape indexes
THESIS = {
    "G_1-1": ([100, 98, 94, 88.5, 83, 78, 16, 0], 30), "G_1-2": ([100, 95, 88.5, 83, 78, 16, 4.5, 0], 30),
    "G_1-3": ([100, 92, 84, 78, 16, 9.5, 3.5, 0], 30), "G_1-4": ([100, 89, 78, 16, 9.5, 6.5, 2.5, 0], 30),
    "G_1-5": ([100, 78, 16, 9.5, 6.5, 3.5, 1.5, 0], 30), "G_2-1": ([100, 99.5, 97.5, 90, 4, 1.5, 0.5, 0], 30),
    "G_2-2": ([100, 96.5, 92.5, 84, 10, 5.5, 2.5, 0], 30), "G_2-3": ([100, 93.5, 87.5, 78, 16, 9.5, 4.5, 0], 30),
    "G_2-4": ([100, 90.5, 82.5, 72, 22, 13.5, 6.5, 0], 30), "G_2-5": ([100, 87.5, 77.5, 66, 28, 17.5, 8.5, 0], 30),
    "G_3-1": ([100, 93.5, 87.5, 78, 16, 9.5, 4.5, 0], 10), "G_3-2": ([100, 93.5, 87.5, 78, 16, 9.5, 4.5, 0], 20),
    "G_3-3": ([100, 93.5, 87.5, 78, 16, 9.5, 4.5, 0], 30), "G_3-4": ([100, 93.5, 87.5, 78, 16, 9.5, 4.5, 0], 40),
    "G_3-5": ([100, 93.5, 87.5, 78, 16, 9.5, 4.5, 0], 50),
}


def forms_dataset(name, b_mm, mass, a_mm=None, c_mm=None):
    """A minimal form database (only what validation_row and the study read)."""
    b = np.asarray(b_mm, float) * 1e-3
    a = b * 1.2 if a_mm is None else np.asarray(a_mm, float) * 1e-3
    c = b * 0.8 if c_mm is None else np.asarray(c_mm, float) * 1e-3
    from ballaststudy.standards import percent_passing
    pp = percent_passing(b, mass)
    return xr.Dataset(
        {"a": ("stone", a, {"units": "m", "long_name": "a"}), "b": ("stone", b, {"units": "m", "long_name": "b"}),
         "c": ("stone", c, {"units": "m", "long_name": "c"}),
         "mass": ("stone", np.asarray(mass, float), {"units": "kg", "long_name": "mass"}),
         "objective_percent_passing": ("sieve", pp, {"units": "percent", "long_name": "objective"})},
        coords={"sieve": ("sieve", np.array(GRADING_SIEVES_MM) * 1e-3, {"units": "m"})},
        attrs={"database": name, "objective_total_mass_kg": float(np.sum(mass)),
               "objective_shape_index_pct": 30.0, "objective_particle_length_index_pct": 1.0,
               "objective_flakiness_index_pct": -1.0})


def forms_from_grading(name, grading, shape_index=0.0):
    """One stone per sieve interval at the interval's geometric middle, mass = the grading's
    step (kg = percentage points / 10), so the generated grading equals `grading`. A share
    `shape_index` % of every stone's mass is split off as a non-cubic twin (c = 0.3 b)."""
    sieves = list(GRADING_SIEVES_MM) + [4.0]
    pp = list(grading) + [0.0]
    b, m, a, c = [], [], [], []
    for k in range(len(GRADING_SIEVES_MM)):
        step = pp[k] - pp[k + 1]
        if step <= 0:
            continue
        mid = np.sqrt(sieves[k] * sieves[k + 1])
        for frac, cb in ((1 - shape_index / 100, 0.8), (shape_index / 100, 0.3)):
            if frac > 0:
                b.append(mid), m.append(step / 10 * frac), a.append(1.2 * mid), c.append(cb * mid)
    return forms_dataset(name, b, m, a, c)


def metrics_dataset(series, units=None, database=None, case=None):
    """metrics.nc content from {name: 1D array over cycles} (missing behaviours = 0)."""
    n = len(next(iter(series.values())))
    data = {}
    for name, unit in UNITS.items():
        v = np.asarray(series.get(name, np.zeros(n)), float)
        data[name] = ("cycle", v, {"units": (units or {}).get(name, unit), "long_name": name})
    attrs = {}
    if database is not None:
        attrs = {"database": database, "case": case}
    return xr.Dataset(data, coords={"cycle": np.arange(n)}, attrs=attrs)


def planted_datasets(rng, databases=THESIS, n_cases=4, n_cycles=12, settlement_of_fines=None, jump=True):
    """Forms {database: Dataset} and metrics {(database, case): Dataset} of a thesis-like study
    with planted behaviour: final settlement a hinge in the fines x at 17 % (2 mm + 0.05 mm/%
    below, 6 mm + 0.4 mm/% above), GP = 10 + 2 x settlement (mm) + noise, VR rising with mean
    size and falling with fines, FPA ~ 55 deg flat except high fines (fluctuating), BR ~ 0.2 %
    noise without trend."""
    from ballaststudy.study.aggregate import database_coordinates
    metrics, forms = {}, {}
    settlement_of_fines = settlement_of_fines or (
        lambda x: 2e-3 + 5e-5 * x if x < 17 else 6e-3 + 4e-4 * (x - 17.5))
    for name, (grading, si) in databases.items():
        fds = forms[name] = forms_from_grading(name, grading, si)
        coords = database_coordinates(fds)
        x, size_mm = coords["percent_passing_22_4mm"], coords["mean_size"] * 1e3
        for case in range(n_cases):
            t = np.linspace(0, 1, n_cycles)
            s_final = settlement_of_fines(x) if jump else 3e-3
            s_final = s_final + rng.normal(0, 2e-4)
            settlement = s_final * np.sqrt(t)
            ghost_final = 10 + 2 * s_final * 1e3 + rng.normal(0, 0.3)
            ghost = np.full(n_cycles, ghost_final)
            vr = 0.25 + 0.003 * (size_mm - 30) - 0.001 * x + rng.normal(0, 0.002) + np.zeros(n_cycles)
            fpa_sd = 3.0 if x > 16 else 0.2
            fpa = 55 + rng.normal(0, fpa_sd, n_cycles)
            br = np.abs(rng.normal(0.002, 0.0005)) * t
            broken = np.round(br * PLANTED_ELEMENTS)
            series = {"settlement": settlement, "ghost_particles": ghost, "void_ratio": vr, "fpa": fpa,
                      "fpa_left": fpa, "fpa_right": fpa, "breakage_rate": br, "breakage_rate_tension": br / 2,
                      "breakage_rate_shear": br / 2, "mean_coordination": np.full(n_cycles, 3.5),
                      "broken_tension": np.floor(broken / 2), "broken_shear": broken - np.floor(broken / 2),
                      "breakages_per_cycle": np.diff(broken, prepend=0.0)}
            metrics[(name, case)] = metrics_dataset(series)
    return metrics, forms


def planted_study_inputs(tmp_path, rng, **kw):
    """`planted_datasets` written as forms/<database>.nc and cases/<database>/case_<k>/metrics.nc;
    returns ({(database, case): path}, {database: path})."""
    metrics, forms = planted_datasets(rng, **kw)

    def write(ds, rel):
        p = tmp_path / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(p)
        return p
    return ({(db, c): write(ds, f"cases/{db}/case_{c:02d}/metrics.nc") for (db, c), ds in metrics.items()},
            {db: write(ds, f"forms/{db}.nc") for db, ds in forms.items()})


def planted_study(rng, **kw):
    """`planted_datasets` as a study Dataset built in memory (cheap even at the thesis' 10 cases x
    1000 cycles)."""
    from ballaststudy.study.aggregate import build_study
    metrics, forms = planted_datasets(rng, **kw)
    return build_study({k: ("{}/{}".format(*k), ds) for k, ds in metrics.items()},
                       {k: (k, ds) for k, ds in forms.items()})


@pytest.fixture
def synth():
    return types.SimpleNamespace(forms_dataset=forms_dataset, forms_from_grading=forms_from_grading,
                                 metrics_dataset=metrics_dataset, planted=planted_study_inputs,
                                 planted_study=planted_study, THESIS=THESIS)


@pytest.fixture(scope="module")
def thesis_study(tmp_path_factory):
    """A planted thesis-like study.nc (15 databases x 4 cases x 12 cycles), loaded."""
    from ballaststudy.study import aggregate
    tmp = tmp_path_factory.mktemp("thesis_study")
    metrics, forms = planted_study_inputs(tmp, np.random.default_rng(5))
    out = aggregate(metrics, forms, tmp / "study.nc")
    with xr.open_dataset(out) as ds:
        return out, ds.load()
