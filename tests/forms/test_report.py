"""forms.report: the validation table and the figures like thesis Figs. 3-9 ... 3-16."""

import pandas as pd
import pytest
import xarray as xr

from ballaststudy.cli import main
from ballaststudy.forms.report import write_report

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
DATABASES = """\
defaults:
  mass_kg: 5
  flakiness_index: null
  particle_length_index: 1
  materials:
    hard: {mass_fraction: 0.7, density_kg_m3: 2850}
    soft: {mass_fraction: 0.3, density_kg_m3: 2620}
databases:
  G_1-5:
    group: 1
    grading: [100, 78, 16, 9.5, 6.5, 3.5, 1.5, 0]
    shape_index: 30
  box_test:
    group: box_test
    grading: G_CRB B
    shape_index: SI_RB 5/30
    particle_length_index: L_RB B
    flakiness_index: FI_RB 35
"""
EXPECTED = ["validation.csv", "fig_3-9_stones.png", "fig_3-10_grading_group1.png", "fig_grading_box_test.png",
            "fig_3-13_particle_numbers.png", "fig_3-14_mass.png", "fig_3-15_shape_index.png",
            "fig_3-16_particle_length.png"]


@pytest.fixture(scope="module")
def datasets(tmp_path_factory):
    """Two small (5 kg) databases from two groups, generated through the CLI."""
    tmp = tmp_path_factory.mktemp("forms")
    (tmp / "databases.yaml").write_text(DATABASES)
    (tmp / "config.yaml").write_text(f"seed: 7\ndatabases_file: {tmp / 'databases.yaml'}\n"
                                     f"databases: all\nresults_dir: {tmp / 'results'}\nforms: {{}}\n")
    assert main(["forms", "generate", "--all", "--out", str(tmp / "db"), "--config",
                 str(tmp / "config.yaml"), "--quiet"]) == 0
    out = []
    for name in ("box_test", "G_1-5"):  # deliberately not in report order
        with xr.open_dataset(tmp / "db" / f"{name}.nc") as ds:
            out.append(ds.load())
    return out


def test_write_report_files_and_table(datasets, tmp_path):
    paths = write_report(datasets, tmp_path / "report", n_stones=3, seed=1)
    assert sorted(p.name for p in paths) == sorted(EXPECTED)
    for name in EXPECTED:
        path = tmp_path / "report" / name
        assert path.is_file() and path.stat().st_size > 0
        if name.endswith(".png"):
            assert path.read_bytes().startswith(PNG_SIGNATURE)
    assert not [p for p in (tmp_path / "report").iterdir() if p.name.startswith(".")]  # no temp files left

    table = pd.read_csv(tmp_path / "report" / "validation.csv")
    assert list(table.database) == ["G_1-5", "box_test"]  # group order, box_test last
    counts = {ds.attrs["database"]: ds.sizes["stone"] for ds in datasets}
    assert dict(zip(table.database, table.particle_count)) == counts
    assert {"objective_mass_kg", "si_pct", "objective_li_pct", "passing_31.5mm_pct"} <= set(table.columns)


def test_write_report_more_stones_than_database(datasets, tmp_path):
    small = datasets[1].isel(stone=slice(0, 2))  # keeps the ragged arrays, fine for the first stones
    paths = write_report([small], tmp_path, n_stones=5)
    assert [p.name for p in paths] == ["validation.csv", "fig_3-9_stones.png", "fig_3-10_grading_group1.png",
                                       "fig_3-13_particle_numbers.png", "fig_3-14_mass.png",
                                       "fig_3-15_shape_index.png", "fig_3-16_particle_length.png"]
