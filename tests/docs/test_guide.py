"""The user guide builds strictly: `sphinx-build -W` (every warning an error: a broken
cross-reference, a page in no table of contents, bad Markdown, a help text that is not
valid reStructuredText), with the reference pages written from the code at build time."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_guide_builds_without_warnings(tmp_path):
    out = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                          "-d", str(tmp_path / "doctrees"), str(ROOT / "docs"), str(tmp_path / "html")],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-4000:]
    for page in ("index", "reference/cli", "reference/generated/config", "reference/generated/modifiers"):
        assert (tmp_path / "html" / f"{page}.html").is_file(), page
