"""examples/python/quickstart.ipynb runs top to bottom without an error, and
its cells print what they promise (CI executes it here, in .ci/run's pytest)."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

NOTEBOOK = Path(__file__).resolve().parents[2] / "examples" / "python" / "quickstart.ipynb"


def test_quickstart_notebook_executes(tmp_path: Path) -> None:
    nbformat = pytest.importorskip("nbformat", reason='pip install "./python[test]"')
    nbclient = pytest.importorskip("nbclient", reason='pip install "./python[test]"')
    nb = nbformat.read(NOTEBOOK, as_version=4)
    os.environ.setdefault("MPLBACKEND", "Agg")
    started = time.perf_counter()
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    elapsed = time.perf_counter() - started
    print(f"quickstart.ipynb executed in {elapsed:.1f} s")
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    # Clean outputs: no warning, no progress-bar lines, nothing on stderr.
    noise = [o for o in outputs if o.get("output_type") == "stream" and o.get("name") == "stderr"]
    assert not noise, "".join(o.get("text", "") for o in noise)
    shown = "".join(str(o.get("text", "")) + str(o.get("data", {}).get("text/plain", "")) for o in outputs)
    assert "Warning" not in shown and "it/s" not in shown, shown
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert "FTAFTSMC: completed" in text and "ISE x" in text, text
    assert "completed" in text.split("ISE x")[-1], text
