"""The loop's outputs: loop.nc (every curve, dataset.py), chosen.yaml, curves.png (plots.py)
and report.md (markdown.py), each from one outcome.LoopRun and the numbers statistics.py
computes from it once."""
import yaml

from ..atomic import atomic_path
from ..scenario.mapping import mapping_kinds
from .dataset import loop_dataset
from .markdown import report_markdown
from .plots import plot_curves
from .statistics import loop_statistics


def write_outputs(out, run):
    """Write the outputs of ``run`` (an outcome.LoopRun) into the folder ``out``, each
    atomically; [report.md, loop.nc, chosen.yaml, curves.png] (report.md first: the
    provenance record sits beside it)."""
    stats = loop_statistics(run)
    files = [out / "report.md", out / "loop.nc", out / "chosen.yaml", out / "curves.png"]
    with atomic_path(files[1]) as tmp:
        loop_dataset(run, stats).to_netcdf(tmp)
    with atomic_path(files[2]) as tmp:
        tmp.write_text(yaml.safe_dump(chosen_doc(stats, run.base, run.mapping), sort_keys=False))
    plot_curves(files[3], run, stats)
    with atomic_path(files[0]) as tmp:
        tmp.write_text(report_markdown(run, stats))
    return files


def chosen_doc(stats, base, mapping=None):
    """chosen.yaml: the effect chosen (or none), the verdict's class, its fitted parameters and 90 % intervals, the
    material parameters it was fitted on and the stress mapping ({test: record}) the tests
    ran under."""
    row = stats.chosen_row
    return {"effect": row["effect"] if row else "none", "verdict": stats.verdict[0],
            "parameters": dict(zip(row["parameters"], row["mean"])) if row else {},
            "interval90": dict(zip(row["parameters"], row["interval90"])) if row else {},
            "material_parameters": base or "table_4_2",
            "stress_mapping": mapping_kinds(mapping or {})}
