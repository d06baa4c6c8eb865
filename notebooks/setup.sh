#!/usr/bin/env bash
# Makes notebooks/.venv (idempotent): Mitsuba 3 + drjit for the reference renders,
# NumPy and matplotlib for the figures, nbclient + ipykernel to execute the notebooks.
# Installs only when requirements.txt changed since the last install. The llvm
# variants of Mitsuba also need LLVM 19 (Debian: apt-get install libllvm19).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
    py=${PYTHON:-$(command -v python3.11 || command -v python3)}
    "$py" -m venv "$venv"
fi
if ! cmp -s "$here/requirements.txt" "$venv/.installed-requirements.txt"; then
    "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
    "$venv/bin/python" -m ipykernel install --sys-prefix --name python3 >/dev/null
    cp "$here/requirements.txt" "$venv/.installed-requirements.txt"
fi
