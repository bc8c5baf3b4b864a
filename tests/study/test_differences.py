"""The screening of the thesis' headline (study/differences.py) on planted levels: a level
with a planted jump of G_1-1 over G_1-2 is read as holding, one without (the negative
control) as not; the differences, intervals and core-hours are the planted ones."""
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from ballaststudy.cli import main
from ballaststudy.config import load_config
from ballaststudy.study.differences import CONTRASTS, REFERENCE, screening_table, write_differences
from ballaststudy.study.optimise import JUMP_FACTOR

ROOT = Path(__file__).resolve().parents[2]


def _part(folder, study, fine_m, neighbour_m, seconds, seating_m=np.nan):
    """A part folder: ``study`` with G_1-1's and G_1-2's final settlements planted around
    fine_m and neighbour_m (sd 5 %), every case's seating ``seating_m``, and two jobs of
    ``seconds`` each in its records."""
    s = study.copy(deep=True)
    s["seating"] = s.seating.copy(data=np.full(s.seating.shape, seating_m))
    rng = np.random.default_rng(1)
    dbs = [str(d) for d in s.database.values]
    for db, level in (("G_1-1", fine_m), ("G_1-2", neighbour_m)):
        finals = level * (1 + 0.05 * rng.standard_normal(s.sizes["case"]))
        s["settlement"][dbs.index(db)] = np.linspace(0, 1, s.sizes["cycle"])[None, :] * finals[:, None]
    folder.mkdir()
    s.to_netcdf(folder / "study.nc")
    jobs = [{"output": [f"cases/G_1-1/case{k}/metrics.nc"], "step": "case run", "inputs": {str(k): ""},
             "started": "2026-12-07T00:00:00+00:00", "finished": f"2026-12-07T00:{seconds // 60:02d}:00+00:00"}
            for k in range(2)]
    (folder / "records.json").write_text(json.dumps(jobs))
    return folder, s


@pytest.fixture(scope="module")
def levels(thesis_study, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("differences")
    _, study = thesis_study
    jump, jump_study = _part(tmp / "jump", study, 0.030, 0.002, 1800)
    flat, flat_study = _part(tmp / "flat", study, 0.002, 0.002, 1800, seating_m=0.004)
    return {"jump": jump, "flat": flat}, {"jump": jump_study, "flat": flat_study}


def test_a_planted_jump_holds_and_its_absence_does_not(levels):
    parts, studies = levels
    table = screening_table(parts, n_boot=500, seed=0)
    g1 = table[(table.contrast == "S(G_1-1) - S(G_1-2)") & (table.settlement == "from cycle 0")].set_index("level")
    for level, study in studies.items():
        finals = study.settlement.sel(database=["G_1-1", "G_1-2"]).values[:, :, -1].mean(axis=1)
        row = g1.loc[level]
        assert row.difference_m == pytest.approx(finals[0] - finals[1], rel=1e-12)
        assert row.difference_lo_m <= row.difference_m <= row.difference_hi_m
    assert g1.loc["jump", "mark"] == "holds"
    assert g1.loc["jump", "difference_lo_m"] > 0.02
    assert g1.loc["flat", "mark"] == "does not hold"          # S - 1.5 S < 0: no jump
    assert g1.loc["flat", "jump_hi_m"] < 0 < g1.loc["flat", "difference_hi_m"]
    assert JUMP_FACTOR > 1
    # with the seating (flat: 4 mm every case): S shifts by it, the difference does not, and
    # the jump's statistic S - 1.5 S moves by -0.5 x 4 mm; no seating recorded: no such rows
    seated = table[(table.contrast == "S(G_1-1) - S(G_1-2)") & (table.settlement == "with the seating")]
    assert seated.level.tolist() == ["flat"]
    assert seated.S_fine_m.iloc[0] == pytest.approx(g1.loc["flat", "S_fine_m"] + 0.004)
    assert seated.difference_m.iloc[0] == pytest.approx(g1.loc["flat", "difference_m"])
    assert table.core_hours.tolist() == pytest.approx([1.0] * len(table))     # two jobs of 30 min
    assert (table.cases == studies["jump"].cycles_run.values.astype(bool).sum()).all()


def test_the_record_is_written_by_the_command(levels, tmp_path):
    parts, _ = levels
    args = [f"{k}={v}" for k, v in parts.items()]
    assert main(["study", "differences", *args, "--out", str(tmp_path), "--resamples", "200"]) == 0
    md = (tmp_path / "differences.md").read_text()
    assert "- S(G_1-1) - S(G_1-2), settlement from cycle 0: the jump holds under jump." in md
    assert "- S(G_1-1) - S(G_1-2), settlement with the seating: the jump holds under none" in md
    assert f"ballaststudy study differences {args[0]} {args[1]} --out {tmp_path}" in md
    assert (tmp_path / "differences.png").stat().st_size > 0
    table = pd.read_csv(tmp_path / "differences.csv")
    assert set(table.level) == {"jump", "flat"} and len(table) == 6
    again = tmp_path / "again"
    write_differences(parts, again, "x", n_boot=200, seed=0)
    assert (again / "differences.csv").read_text() == (tmp_path / "differences.csv").read_text()


def test_the_confirmation_is_read_at_its_last_cycle_beside_the_screening(levels, tmp_path):
    """--confirm: its own table (every case at its last cycle, whatever --at-cycle says of the
    screening), its verdicts, its curves and its core-hours in the record."""
    parts, studies = levels
    args = ["study", "differences", f"flat={parts['flat']}", "--out", str(tmp_path), "--resamples", "200",
            "--at-cycle", "3", "--confirm", f"jump={parts['jump']}"]
    assert main(args) == 0
    md = (tmp_path / "differences.md").read_text()
    assert "- S(G_1-1) - S(G_1-2), settlement from cycle 0: the jump holds under none of the levels screened." in md
    assert "- S(G_1-1) - S(G_1-2), settlement from cycle 0: the jump holds under jump." in md
    assert f"--confirm jump={parts['jump']}" in md and "Core-hours in all: 2.0." in md
    confirmation = pd.read_csv(tmp_path / "differences_confirmation.csv")
    row = confirmation[(confirmation.contrast == "S(G_1-1) - S(G_1-2)")].iloc[0]
    finals = studies["jump"].settlement.sel(database="G_1-1").values[:, -1]
    assert row.S_fine_m == pytest.approx(finals.mean()) and row.cycles == studies["jump"].sizes["cycle"]
    assert (tmp_path / "differences_confirmation.png").stat().st_size > 0
    assert main(["study", "differences", f"flat={parts['flat']}", "--out", str(tmp_path / "o"),
                 "--confirm", "jump"]) == 2
    assert not (tmp_path / "o" / "differences.md").exists()


def test_a_longer_run_is_read_at_the_screenings_cycle(levels):
    """--at-cycle: each case at that cycle (the planted curves rise linearly to the last)."""
    parts, studies = levels
    n = studies["jump"].sizes["cycle"]
    table = screening_table({"jump": parts["jump"]}, n_boot=200, seed=0, at_cycle=n // 2 - 1)
    row = table[(table.contrast == "S(G_1-1) - S(G_1-2)") & (table.settlement == "from cycle 0")].iloc[0]
    s = studies["jump"].settlement.sel(database="G_1-1").values[:, n // 2 - 1].mean()
    assert row.S_fine_m == pytest.approx(s) and row.cycles == n // 2


@pytest.mark.parametrize("args, says", [(["jump"], "is not LEVEL=PART"), (["a=x", "a=y"], "given twice"),
                                        (["a=/nonexistent"], "expected a part's study.nc")])
def test_bad_levels_are_one_line(tmp_path, capsys, args, says):
    assert main(["study", "differences", *args, "--out", str(tmp_path / "o")]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and says in line, line
    assert not (tmp_path / "o" / "differences.md").exists()


def _merged(base, *overlays):
    """Snakemake's --configfile A B ...: later files update earlier ones key by key."""
    def update(a, b):
        for k, v in b.items():
            a[k] = update(dict(a.get(k) or {}), v) if isinstance(v, dict) else v
        return a
    cfg = yaml.safe_load(base.read_text())
    for o in overlays:
        cfg = update(cfg, yaml.safe_load(o.read_text()))
    return cfg


def _valid(tmp_path, *files):
    cfg = _merged(ROOT / "config/thesis.yaml", *(ROOT / f"config/differences/{f}.yaml" for f in files))
    cfg["databases_file"] = str(ROOT / cfg["databases_file"])
    path = tmp_path / "merged.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return load_config(path)


LEVELS = sorted(p.stem for p in (ROOT / "config/differences").glob("*.yaml") if p.stem != "screening"
                and not p.stem.startswith("confirm_"))


@pytest.mark.parametrize("level", LEVELS)
def test_every_level_is_a_valid_config_with_its_own_results(level, tmp_path):
    """Each level's overlay on config/thesis.yaml and the screening's is a config the
    workflow accepts, writing to a folder of its own."""
    cfg = _valid(tmp_path, "screening", level)
    assert cfg["results_dir"] == f"results/differences/{level}"
    assert set(cfg["databases"]) == {d for pair in CONTRASTS for d in pair} | {REFERENCE}


@pytest.mark.parametrize("level", [p.stem.removeprefix("confirm_")
                                   for p in sorted((ROOT / "config/differences").glob("confirm_*.yaml"))])
def test_every_confirmation_is_its_level_at_the_thesis_length(level, tmp_path):
    """confirm_<level>.yaml over its level: the contrasts' databases, >= 10 cases x 1000
    cycles, in a folder of its own (not the screening's, whose cases it would overwrite)."""
    assert level in LEVELS
    cfg = _valid(tmp_path, level, f"confirm_{level}")
    assert cfg["results_dir"] == f"results/differences/confirm_{level}"
    assert set(cfg["databases"]) == {d for pair in CONTRASTS for d in pair}
    assert cfg["study"]["cases_per_database"] >= 10 and cfg["rig"]["box"]["loading"]["cycles"] >= 1000
