#!/usr/bin/env python3
"""Executes a notebook cell by cell (nbclient) in a scratch folder; exits non-zero, naming the
cell and its error, if any cell fails. Usage: run_notebook.py NOTEBOOK.ipynb"""
import os
import sys
import tempfile

import nbformat
from nbclient import NotebookClient
from nbclient.exceptions import CellExecutionError


def main():
    if len(sys.argv) != 2:
        print("usage: run_notebook.py NOTEBOOK.ipynb", file=sys.stderr)
        return 2
    path = sys.argv[1]
    nb = nbformat.read(path, as_version=4)
    with tempfile.TemporaryDirectory(prefix="pp5-notebook-") as scratch:
        # Jupyter's and matplotlib's state goes to the scratch folder, not the user's home.
        for var in ("JUPYTER_RUNTIME_DIR", "JUPYTER_DATA_DIR", "IPYTHONDIR", "MPLCONFIGDIR"):
            os.environ[var] = os.path.join(scratch, var.lower())
        # The kernel draws with matplotlib's inline backend, as in Jupyter.
        os.environ.pop("MPLBACKEND", None)
        client = NotebookClient(nb, timeout=600, kernel_name="python3",
                                resources={"metadata": {"path": scratch}})
        try:
            client.execute()
        except CellExecutionError as e:
            print(f"{path}: a cell failed:\n{e}", file=sys.stderr)
            return 1
    cells = sum(1 for c in nb.cells if c.cell_type == "code")
    print(f"{path}: {cells} code cells ran")
    return 0


if __name__ == "__main__":
    sys.exit(main())
