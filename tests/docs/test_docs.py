"""The documentation builds with Sphinx, warnings as errors (issue 26 item 2): every page in the
toctree, every link between pages, every docstring of the API reference."""

import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_docs_build_without_warnings(tmp_path):
    result = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                             str(ROOT / "docs"), str(tmp_path / "html")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-4000:]
    assert (tmp_path / "html" / "api.html").read_text().count("solve_mobility") > 0
    assert (tmp_path / "html" / "scene-reference.html").exists()
