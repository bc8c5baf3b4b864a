"""A study run in parts (study/parts.py): merging the parts' study.nc gives the study a whole
run gives; a case run twice, or a database whose forms differ between parts, is refused."""

import numpy as np
import pytest
import xarray as xr

from ballaststudy.config import ConfigError
from ballaststudy.study.aggregate import BEHAVIOURS
from ballaststudy.study.parts import check_one_setting, merge_studies

from .parts import split


def test_merged_parts_are_the_whole_study(thesis_study):
    _, study = thesis_study
    a, b = split(study, 8, 8)
    assert a.sizes["database"] == 9 and b.sizes["database"] == 7      # G_2-4 in both, half its cases each
    merged = merge_studies([("b", b), ("a", a)])                       # the order of the parts does not matter
    xr.testing.assert_equal(merged, study)
    assert merged.cycles_run.dtype == study.cycles_run.dtype
    assert list(merged.group.values) == list(study.group.values)


def test_a_part_with_fewer_cycles_is_padded(thesis_study):
    _, study = thesis_study
    a, b = split(study, 8, 8)
    short = b.isel(cycle=slice(0, 5))
    short["cycles_run"] = xr.where(short.cycles_run > 0, 5, 0).astype(np.int32)
    merged = merge_studies([("a", a), ("b", short)])
    assert merged.sizes["cycle"] == study.sizes["cycle"]
    last = merged.sel(database="G_3-5")
    assert (last.cycles_run == 5).all() and np.isnan(last.settlement.values[:, 5:]).all()
    assert np.array_equal(last.settlement.values[:, :5], study.sel(database="G_3-5").settlement.values[:, :5])


def test_a_part_from_before_the_force_ratio_merges(thesis_study):
    """A part packed before study.nc kept the stones' force ratio (docs/thesis-scale/parts)
    merges with one that has it: its cases read NaN."""
    _, study = thesis_study
    study = study.copy()
    planted = np.random.default_rng(0).uniform(1e-3, 1e-2, study.assembly_force_ratio.shape)
    study["assembly_force_ratio"] = study.assembly_force_ratio.copy(data=planted)
    a, b = split(study, 8, 8)
    merged = merge_studies([("a", a.drop_vars("assembly_force_ratio")), ("b", b)])
    ran_in_a = a.cycles_run.values > 0
    got = merged.assembly_force_ratio.sel(database=a.database.values).values
    assert np.isnan(got[ran_in_a]).all()
    only_b = [d for d in b.database.values if d not in a.database.values]
    np.testing.assert_array_equal(merged.assembly_force_ratio.sel(database=only_b).values,
                                  study.assembly_force_ratio.sel(database=only_b).values)


def test_a_case_in_two_parts_is_refused(thesis_study):
    _, study = thesis_study
    a, b = split(study, 8, 8)
    with pytest.raises(ConfigError, match="G_2-4 case 0 is also in a"):
        merge_studies([("a", a), ("a2", a.sel(database=["G_2-4"]))])
    with pytest.raises(ConfigError, match="G_1-1 case 0 is also in a"):
        merge_studies([("a", a), ("b", b), ("whole", study)])


def test_parts_with_other_form_databases_are_refused(thesis_study):
    _, study = thesis_study
    a, b = split(study, 8, 8)
    b = b.assign_coords(percent_passing_22_4mm=b.percent_passing_22_4mm + 0.5)   # another G_2-4 database
    with pytest.raises(ConfigError, match="G_2-4: its form database differs"):
        merge_studies([("a", a), ("b", b)])
    with pytest.raises(ConfigError, match="no parts"):
        merge_studies([])


def test_every_behaviour_survives_the_merge(thesis_study):
    _, study = thesis_study
    merged = merge_studies(list(zip("ab", split(study, 3, 3))))
    for name in BEHAVIOURS:
        assert np.array_equal(merged[name].values, study[name].values, equal_nan=True), name


def test_parts_run_with_other_settings_are_refused(tmp_path):
    def run(rig, case=0):
        return {"step": "case run", "params": {"cycles": 1000, "rig": rig, "scenario_key": f"specimen{case}"},
                "output": {f"m{case}": "0"}}

    def assemble(case):
        return {"step": "case assemble", "params": {"case": case, "rig": {"width_m": 0.34}}, "output": {f"a{case}": "0"}}

    same = [("a", {"m0": run({"cyclic_v_max_m_s": 0.1}), "a0": assemble(0)}),
            ("b", {"m1": run({"cyclic_v_max_m_s": 0.1}, 1), "a1": assemble(1),
                   "s": {"step": "study aggregate", "params": {"x": 1}, "output": {}}})]
    check_one_setting(same)                        # cases and study steps may differ: one study
    other = same + [("c", {"m2": run({"cyclic_v_max_m_s": 0.2}, 2)})]
    with pytest.raises(ConfigError, match=r"c: case run.params.rig.cyclic_v_max_m_s: differs from the same "
                                          r"step's in a"):
        check_one_setting(other)
