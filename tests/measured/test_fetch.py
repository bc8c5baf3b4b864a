"""`measured fetch` and the workflow's measured_fetch: the public curves downloaded from a
server (here a local one serving the development machines' copy of the source, as CI reaches
no repository), each checked by its SHA-256; a changed file or a dead link refused in one
line, nothing written for it."""
import filecmp
import shutil
import socket
import subprocess
from pathlib import Path

import pytest
import yaml

from ballaststudy.cli import main
from ballaststudy.config import ConfigError
from ballaststudy.measured.fetch import fetch, registered_files
from ballaststudy.measured.importer import load_conditions

from .served import LOCAL_COPY, served

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(not LOCAL_COPY.is_dir(), reason=f"no local copy of the source at {LOCAL_COPY}")


def _dead_url():
    """A URL on a port nothing listens on."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"http://127.0.0.1:{s.getsockname()[1]}/"


def test_fetch_brings_every_registered_file_and_keeps_it(tmp_path):
    with served(LOCAL_COPY) as url:
        paths = fetch(tmp_path, url)
    assert [p.relative_to(tmp_path).as_posix() for p in paths] == registered_files()
    assert all(filecmp.cmp(p, LOCAL_COPY / p.relative_to(tmp_path), shallow=False) for p in paths)
    assert fetch(tmp_path, _dead_url()) == paths       # all there and checked: nothing downloaded


def test_a_changed_file_is_refused_and_not_written(tmp_path, capsys):
    source = shutil.copytree(LOCAL_COPY, tmp_path / "source")
    changed = registered_files()[-1]
    with open(source / changed, "a") as f:
        f.write("1, 2\n")
    data = tmp_path / "data"
    with served(source) as url:
        with pytest.raises(ConfigError, match="refused: not the registered file") as err:
            fetch(data, url, names=[changed])
        assert err.value.file == url + changed
        assert main(["measured", "fetch", "--data-dir", str(data), "--url", url, "--quiet"]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and changed in line and "refused" in line, line
    assert not (data / changed).exists()
    assert (data / registered_files()[0]).is_file()      # those before it came, checked


def test_no_connection_is_one_line(tmp_path, capsys):
    assert main(["measured", "fetch", "--data-dir", str(tmp_path / "data"), "--url", _dead_url()]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "could not be downloaded" in line, line
    assert not any((tmp_path / "data").rglob("*.*"))


def test_an_unregistered_name_is_refused(tmp_path):
    with pytest.raises(ConfigError, match="not a registered curve file"):
        fetch(tmp_path, _dead_url(), names=["sun_et_al_16/nothing.dat"])


def test_every_curve_the_shipped_tests_read_is_registered():
    registered = set(registered_files())
    for path in sorted((ROOT / "config" / "measured").rglob("*.yaml")):
        files = {c["file"] for c in load_conditions(path)["curves"]}
        assert files <= registered, (path, files - registered)


def test_the_workflow_fetches_what_a_target_needs(tmp_path):
    """A target that reads the curves fetches them first (one job); `all` runs without them
    and says how to fetch them."""
    for part in ("workflow", "config"):
        src = ROOT / part
        shutil.copytree(src, tmp_path / part) if src.is_dir() else shutil.copy(src, tmp_path)
    cfg_path = tmp_path / "config" / "config.yaml"
    cfg = yaml.safe_load(cfg_path.read_text())
    plan = subprocess.run(["snakemake", "-n", "all"], cwd=tmp_path, capture_output=True, text=True)
    assert plan.returncode == 0 and "measured_fetch" in plan.stderr and "measured_import" not in plan.stdout
    with served(LOCAL_COPY) as url:
        cfg["measured"]["source_url"] = url
        cfg_path.write_text(yaml.safe_dump(cfg))
        run = subprocess.run(["snakemake", "--cores", "1", "results/measured/sun_et_al_16/p60_q230_f5.nc"],
                             cwd=tmp_path, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stderr.count("rule measured_fetch_files:") == 1 and run.stderr.count("rule measured_import:") == 1
    assert all((tmp_path / "resources" / "measured" / name).is_file() for name in registered_files())
    assert (tmp_path / "results" / "measured" / "sun_et_al_16" / "p60_q230_f5.nc").is_file()
