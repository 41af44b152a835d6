"""Notebook 02 (Sections V-VI: flapping and combined model) runs top to bottom with nbclient,
in a fresh kernel of this virtual environment, from a temporary working folder."""

from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "02_flapping_and_combined.ipynb"


@pytest.mark.slow
def test_flapping_notebook_runs(tmp_path):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    errors = [f"{o['ename']}: {o['evalue']}" for o in outputs if o.get("output_type") == "error"]
    assert not errors, errors
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    # the notebook shows the paper's tables and figures
    for marker in ("Table 7:", "Table 8, estimation data:", "validation phase offset",
                   "combined simulation, validation flight:", "finite: True"):
        assert marker in text, marker
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 6  # Figures 12-17
