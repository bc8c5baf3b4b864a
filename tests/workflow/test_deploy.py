"""The workflow deployed as the Snakemake workflow catalog deploys one: `snakedeploy
deploy-workflow` from a clone of this repository into an empty folder writes a Snakefile
that uses the workflow as a module, with the config, profiles and licence beside it; the
deployment dry-runs the default job on the copied config.

snakedeploy's local provider writes the module's Snakefile as a path relative to the
deployment (`workflow/Snakefile`), which Snakemake reads as the deployment's own file; a
deployment from GitHub names the repository instead (`github(..., path=
"workflow/Snakefile")`). The test points the module at the clone's Snakefile, as that does."""
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _run(cmd, cwd):
    out = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    assert out.returncode == 0, f"{' '.join(map(str, cmd))}:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}"
    return out


def test_snakedeploy_deployment_dry_runs(tmp_path):
    clone, dest = tmp_path / "clone", tmp_path / "deployed"
    _run(["git", "clone", "-q", str(ROOT), str(clone)], tmp_path)
    _run([Path(sys.executable).with_name("snakedeploy"), "deploy-workflow", str(clone), str(dest),
          "--branch", "HEAD"], tmp_path)
    snakefile = dest / "workflow" / "Snakefile"
    text = snakefile.read_text()
    assert "use rule * from" in text and '"workflow/Snakefile"' in text
    assert (dest / "config" / "config.yaml").is_file() and (dest / "config" / "README.md").is_file()
    assert (dest / "profiles" / "slurm").is_dir() and (dest / "LICENSE").is_file()
    snakefile.write_text(text.replace('"workflow/Snakefile"', f'"{clone / "workflow" / "Snakefile"}"'))
    shutil.rmtree(clone / "src")        # as from GitHub: the module has its workflow/, the package is installed
    plan = _run(["snakemake", "-n"], dest)
    assert "forms_generate" in plan.stdout and "study_optimise" in plan.stdout
    assert "measured_fetch" in plan.stderr            # the note on the measured curves
