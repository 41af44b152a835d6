"""Notebook 03 (sensitivities through the pipeline) runs top to bottom with nbclient, in a
fresh kernel of this virtual environment, from a temporary working folder."""

from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).resolve().parents[1] / "notebooks" / "03_sensitivities.ipynb"


@pytest.mark.slow
def test_sensitivities_notebook_runs(tmp_path):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    client = NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    errors = [f"{o['ename']}: {o['evalue']}" for o in outputs if o.get("output_type") == "error"]
    assert not errors, errors
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    for marker in ("fit converged: True", "short-period mode:",
                   "most influential on the short-period eigenvalue:", "sum over Mq Mu Mw Mde",
                   "max |dJ/dtheta * std| at the estimate:", "Newton step left at the estimate",
                   "max |θ(c)-θ(5)| over 4-6 Hz"):
        assert marker in text, marker
    # Euler's identity printed by the notebook: the two numbers agree
    line = next(ln for ln in text.splitlines() if ln.startswith("sum over Mq Mu Mw Mde"))
    total, iy = (float(x) for x in line.replace("Iy:", ":").split(":")[1:3])
    assert total == pytest.approx(-iy, rel=1e-6, abs=1e-9)
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 4  # the three figures of sensitivities and the refits
