"""IRI tables on planted relations: settlement = 2 x ghost + noise -> positive; FPA falling
with settlement -> negative; void ratio and breakage independent -> none; too few samples
-> not decidable. Also the per-case summaries with NaN padding."""

import argparse

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from ballaststudy.config import ConfigError
from ballaststudy.study import iri_table, stats, write_iri
from ballaststudy.study.cli import register
from ballaststudy.study.iri import THESIS_IRI, scale_note, thesis_mark, thesis_table


def planted(n_db=6, n_case=5, n_cycle=4, seed=1):
    rng = np.random.default_rng(seed)
    shape = (n_db, n_case)
    dg = rng.uniform(0, 10, shape)                      # ghost change (start at 0)
    s_final = 2 * dg + rng.normal(0, 0.5, shape)        # settlement: planted on ghost
    t = np.linspace(0, 1, n_cycle)
    ghost = dg[..., None] * t
    settlement = s_final[..., None] * t
    fpa = 55 + (-0.8 * s_final + rng.normal(0, 1, shape))[..., None] * t
    vr = rng.uniform(0.2, 0.4, shape + (n_cycle,))      # independent, varies every cycle
    br = rng.uniform(0, 0.01, shape + (n_cycle,))
    dims = ("database", "case", "cycle")
    return xr.Dataset({"settlement": (dims, settlement), "ghost_particles": (dims, ghost), "fpa": (dims, fpa),
                       "void_ratio": (dims, vr), "breakage_rate": (dims, br)},
                      coords={"database": [f"D{i}" for i in range(n_db)], "case": np.arange(n_case),
                              "cycle": np.arange(n_cycle)})


def _row(table, iri, kind):
    return table[(table.iri == iri) & (table.kind == kind)].iloc[0]


def test_planted_verdicts():
    table = iri_table(planted(), n_boot=1000, seed=3)
    assert len(table) == 20 and set(table.kind) == {"final", "change"}
    assert set(table.iri) == {f"IRI_{a}-{b}" for a, b in [("BS", "BR"), ("BS", "GP"), ("BS", "FPA"), ("BS", "VR"),
                                                          ("BR", "GP"), ("BR", "FPA"), ("BR", "VR"), ("GP", "FPA"),
                                                          ("GP", "VR"), ("FPA", "VR")]}
    for kind in ("final", "change"):
        bs_gp = _row(table, "IRI_BS-GP", kind)
        assert bs_gp.verdict == "positive", bs_gp.to_dict()
        assert bs_gp.spearman_lo <= bs_gp.spearman_rho <= bs_gp.spearman_hi
        assert bs_gp.pearson_r > 0.9 and bs_gp.n == 30
        assert _row(table, "IRI_BS-FPA", kind).verdict == "negative"
        assert _row(table, "IRI_GP-FPA", kind).verdict == "negative"
        for iri in ("IRI_BS-VR", "IRI_GP-VR", "IRI_BR-VR"):
            r = _row(table, iri, kind)
            assert r.verdict == "none", r.to_dict()
            assert r.spearman_lo < 0 < r.spearman_hi


def test_bootstrap_is_seeded():
    a = iri_table(planted(), n_boot=300, seed=7)
    b = iri_table(planted(), n_boot=300, seed=7)
    c = iri_table(planted(), n_boot=300, seed=8)
    pd.testing.assert_frame_equal(a, b)
    assert not np.allclose(a.spearman_lo, c.spearman_lo)


def test_too_few_samples_not_decidable():
    small = planted().isel(database=[0], case=slice(0, 5))
    table = iri_table(small, n_boot=200)
    assert (table.verdict == "not decidable").all()
    assert (table.n == 5).all()


def test_verdict_rule_threshold():
    c = {"n": 30, "spearman_rho": 0.25, "spearman_lo": 0.05, "spearman_hi": 0.45}
    assert stats.verdict(c) == "none"              # interval above 0, but |rho| < 0.3
    assert stats.verdict(dict(c, spearman_rho=0.35)) == "positive"
    assert stats.verdict(dict(c, spearman_rho=-0.35, spearman_lo=-0.5, spearman_hi=-0.1)) == "negative"
    assert stats.verdict(dict(c, spearman_rho=0.35, spearman_lo=-0.01)) == "none"


def test_final_and_change_use_last_run_cycle():
    s = np.array([[1.0, 2.0, 5.0, np.nan], [np.nan, 3.0, 4.0, 9.0], [np.nan] * 4])
    np.testing.assert_allclose(stats.final_value(s), [5.0, 9.0, np.nan])
    np.testing.assert_allclose(stats.change_value(s), [4.0, 6.0, np.nan])
    np.testing.assert_allclose(stats.level_value(s), [8 / 3, 16 / 3, np.nan])


def test_verdicts_kept_below_the_thesis_scale():
    # the verdicts describe the samples at any scale; only the note says the run is short
    short, full = planted(n_case=5, n_cycle=4), planted(n_case=10, n_cycle=1000)
    assert scale_note(short).startswith("**Far below the thesis' scale.**") and scale_note(full) == ""
    assert _row(iri_table(short, n_boot=500, seed=3), "IRI_BS-GP", "final").verdict == "positive"
    assert _row(iri_table(full, n_boot=500, seed=3), "IRI_BS-GP", "final").verdict == "positive"


def test_write_iri_files_and_cli(tmp_path):
    study = planted()
    paths = write_iri(study, tmp_path / "iri", n_boot=200)
    assert [p.name for p in paths] == ["iri.csv", "iri_thesis.csv", "iri.md", "iri_heatmap.png"]
    assert len(pd.read_csv(paths[0])) == 20
    assert len(pd.read_csv(paths[1])) == 10
    md = paths[2].read_text()
    assert "## Beside thesis Table 5-2" in md and "not decidable at this scale" in md
    assert "Verdict rule" in md and "|rho| >= 0.3" in md and "IRI_BS-GP" in md
    assert md.splitlines()[2].startswith("**Far below the thesis' scale.** This study ran 5 cases per database "
                                         "and 4 load cycles per case")
    assert paths[3].stat().st_size > 1000
    # CLI: a study file without the behaviours is refused with its name
    bad = tmp_path / "not_a_study.nc"
    study.drop_vars("void_ratio").to_netcdf(bad)
    p = argparse.ArgumentParser()
    register(p.add_subparsers(dest="stage"))
    args = p.parse_args(["study", "iri", str(bad), "--out", str(tmp_path / "x")])
    with pytest.raises(ConfigError, match="not_a_study.nc"):
        args.func(args)
    with pytest.raises(SystemExit):     # refused by the parser (argtypes), before any work
        p.parse_args(["study", "iri", str(bad), "--out", str(tmp_path / "x"), "--resamples", "5"])
    assert not (tmp_path / "x").exists()


def test_thesis_marks_on_planted_relations():
    # planted(): GP and BS rise together; FPA changes the more, the more the case settles (its
    # sd over cycles ~ 0.8 x final settlement); VR and BR independent of everything
    table = thesis_table(planted(n_case=10, n_cycle=100), n_boot=500, seed=2).set_index("iri")
    assert len(table) == 10 and set(table.index) == {f"IRI_{a}-{b}" for a, b, *_ in THESIS_IRI}
    assert table.loc["IRI_BS-GP", ["verdict", "mark"]].tolist() == ["positive", "holds"]
    # the thesis' "radically changing" angle: settlement against the angle's sd over cycles
    assert table.loc["IRI_BS-FPA", ["quantity_b", "verdict", "mark"]].tolist() == ["variability", "positive", "holds"]
    assert table.loc["IRI_GP-FPA", ["verdict", "mark"]].tolist() == ["positive", "holds"]
    for iri in ("IRI_BS-VR", "IRI_GP-VR"):       # thesis: negative; planted: none
        assert table.loc[iri, ["verdict", "mark"]].tolist() == ["none", "does not hold"], iri
    for iri in ("IRI_BS-BR", "IRI_BR-GP", "IRI_BR-FPA", "IRI_BR-VR", "IRI_FPA-VR"):   # thesis and planted: none
        assert table.loc[iri, ["verdict", "mark"]].tolist() == ["none", "holds"], iri
    assert (table["mark"] == table["mark_by_rule"]).all()


def test_thesis_marks_rule_and_scale():
    assert thesis_mark("negative", "negative") == "holds"
    assert thesis_mark("negative", "positive") == "does not hold"
    assert thesis_mark("none", "negative") == "does not hold"
    assert thesis_mark("positive", "not decidable") == "not decidable"
    short = thesis_table(planted(n_case=5, n_cycle=4), n_boot=300, seed=2).set_index("iri")
    assert short.loc["IRI_BS-GP", ["verdict", "mark", "mark_by_rule"]].tolist() == \
        ["positive", "not decidable at this scale", "holds"]
