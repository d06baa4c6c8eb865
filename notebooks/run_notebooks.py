"""Executes the notebooks with nbclient, in memory (the stored files keep no
outputs), and fails on the first cell that raises.

    MIRAGE_BIN=target/release/mirage MIRAGE_SMALL=1 notebooks/.venv/bin/python notebooks/run_notebooks.py [NAME.ipynb ...]

Environment: MIRAGE_BIN (the mirage binary; default: a release build of this
checkout), MIRAGE_SMALL=1 (the small sizes CI uses), MIRAGE_NB_OUT (where the
notebooks write their files; default: a temporary folder per notebook).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

HERE = Path(__file__).resolve().parent
NOTEBOOKS = ["fit_walkthrough.ipynb", "tradeoff.ipynb", "validation.ipynb", "python_api.ipynb",
             "ensemble.ipynb", "photo.ipynb"]


def main(argv: list[str]) -> int:
    names = argv or NOTEBOOKS
    for name in names:
        path = HERE / name
        nb = nbformat.read(path, as_version=4)
        given = os.environ.get("MIRAGE_NB_OUT")
        with tempfile.TemporaryDirectory(prefix="mirage-nb-") as tmp:
            # The kernel inherits this process's environment.
            os.environ["MIRAGE_NB_OUT"] = given or tmp
            t0 = time.perf_counter()
            client = NotebookClient(nb, timeout=900, kernel_name="python3",
                                    resources={"metadata": {"path": str(HERE)}})
            try:
                client.execute()
            finally:
                if given is None:
                    del os.environ["MIRAGE_NB_OUT"]
        print(f"{name}: executed in {time.perf_counter() - t0:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
