"""The documentation builds with Sphinx, warnings as errors: every page in the toctree, every
link between pages, every docstring of the API reference, and a table of fields for every
options class."""

import pathlib
import subprocess
import sys

from tests.docs.test_api_reference import options_classes
from warpbem import SolverOptions
from warpbem.options import declared

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_docs_build_without_warnings(tmp_path):
    result = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                             str(ROOT / "docs"), str(tmp_path / "html")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr[-4000:]
    api = (tmp_path / "html" / "api.html").read_text()
    assert api.count("solve_mobility") > 0
    assert (tmp_path / "html" / "scene-reference.html").exists()
    # one table of fields per options class (docs/_ext/options_table.py), each row's field as code
    assert api.count('class="options-table') == len(options_classes())
    for name, _, _ in declared(SolverOptions):
        assert f'<span class="pre">{name}</span></code></p></td>' in api, name
