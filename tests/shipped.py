"""The shipped config (config/config.yaml) as a test writes it: paths made absolute so it
runs from any folder, a test's change applied, written to a file of the test's."""
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def shipped_config(path, change=None):
    """Write config/config.yaml to ``path`` with its databases file and measured tests'
    folder absolute and ``change(cfg)`` applied (it edits the dict in place). Returns
    ``path``."""
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    cfg["databases_file"] = str(ROOT / cfg["databases_file"])
    cfg["measured"]["tests_dir"] = str(ROOT / cfg["measured"]["tests_dir"])
    if change is not None:
        change(cfg)
    path = Path(path)
    path.write_text(yaml.safe_dump(cfg))
    return path
