#!/usr/bin/env bash
# Makes notebooks/.venv (idempotent): Mitsuba 3 + drjit for the reference renders,
# NumPy and matplotlib for the figures, nbclient + ipykernel to execute the notebooks,
# pytest, and this checkout's Python package `mirage_air` (`pip install .`, built
# by maturin; tests/python.rs runs its suite). Installs the requirements only when
# requirements.txt changed since the last install, and the package only when a
# file it is built from is newer than the last install. The llvm variants of
# Mitsuba also need LLVM 19 (Debian: apt-get install libllvm19).
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
root=$(cd "$here/.." && pwd)
stamp="$venv/.installed-mirage-air"
if [ ! -e "$stamp" ] || [ -n "$(find "$root/src" "$root/python/mirage_air" "$root/Cargo.toml" \
        "$root/Cargo.lock" "$root/pyproject.toml" -newer "$stamp" -print -quit)" ]; then
    echo "== notebooks/.venv: pip install $root (mirage_air)"
    start=$(date +%s)
    "$venv/bin/pip" install --quiet --disable-pip-version-check "$root"
    touch "$stamp"
    echo "== mirage_air installed in $(( $(date +%s) - start )) s"
fi
