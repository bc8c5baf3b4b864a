"""The settings classes' defaults are the thesis-scale config (config/thesis.yaml): code that
builds them without a config (tests, benchmarks, notebooks) gets the study's numbers, and a
number changed in one place but not the other fails here."""
from pathlib import Path

import pytest

from ballaststudy.bpm.params import BpmParams
from ballaststudy.config import load_config
from ballaststudy.metrics import MetricsParams
from ballaststudy.rig.params import RigParams

THESIS = Path(__file__).resolve().parents[2] / "config" / "thesis.yaml"


@pytest.fixture(scope="module")
def thesis():
    return load_config(THESIS)


def test_rig_defaults_are_the_thesis_config(thesis):
    assert RigParams().to_dict() == RigParams.from_config(thesis["rig"]).to_dict()
    stages = RigParams().to_config()["box"]
    for stage in ("assembly", "loading"):       # each key in its stage, none missing
        assert set(thesis["rig"]["box"][stage]) == set(stages[stage]), stage


def test_bpm_defaults_are_the_thesis_config(thesis):
    section = dict(thesis["bpm"])
    assert BpmParams() == BpmParams.from_config(section)


def test_metrics_defaults_are_the_thesis_config(thesis):
    assert MetricsParams() == MetricsParams.from_config(thesis["metrics"])
