"""The README's first command needs only what `pip install -e .` brings: in a fresh virtual
environment (nothing installed by hand), install the package, run a tiny study's forms
stage and write the Snakemake report. Catches a missing install step such as pygments,
which `snakemake --report` imports but snakemake does not declare (1-2 minutes, most of
it pip; wheels come from pip's cache after the first run). pip installs with --no-compile:
writing the bytecode of every installed module took half of pip's time (two fresh installs
side by side: 80 s with, 40 s without), and Python compiles what the run imports anyway, so
no missing dependency can hide behind it."""

import shutil
import subprocess
import sys
import venv
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def _tiny_study(d):
    shutil.copytree(ROOT / "workflow", d / "workflow", symlinks=False)
    (d / "config").mkdir()
    dbs = yaml.safe_load((ROOT / "config" / "databases.yaml").read_text())
    dbs["defaults"]["mass_kg"] = 3
    dbs["databases"] = {"G_1-5": dbs["databases"]["G_1-5"]}
    (d / "config" / "databases.yaml").write_text(yaml.safe_dump(dbs))
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["databases"] = ["G_1-5"]
    cfg["measured"]["tests_dir"] = "config/measured"
    (d / "config" / "config.yaml").write_text(yaml.safe_dump(cfg))


def _run(cmd, cwd, env_bin):
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True,
                         env={"PATH": f"{env_bin}:/usr/bin:/bin", "HOME": str(Path.home())})
    assert out.returncode == 0, f"{' '.join(map(str, cmd))}:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
    return out


def test_fresh_venv_install_then_report(tmp_path):
    env = tmp_path / "venv"
    venv.create(env, with_pip=True)     # no system site-packages: only what pip brings
    bin_dir = env / ("Scripts" if sys.platform == "win32" else "bin")
    _run([bin_dir / "python", "-m", "pip", "install", "-q", "--no-compile", "-e", str(ROOT)], tmp_path, bin_dir)
    study = tmp_path / "study"
    study.mkdir()
    _tiny_study(study)
    _run([bin_dir / "snakemake", "--cores", "2", "forms_report"], study, bin_dir)
    _run([bin_dir / "snakemake", "--report", "report.html", "forms_report"], study, bin_dir)
    assert (study / "report.html").stat().st_size > 10_000
