#!/usr/bin/env bash
# The by-hand baseline comparison in one command, from a fresh checkout:
#
#   bash benches/baseline/compare.sh [PROBLEM.json ...] [--sweep] [--repeats N] [--max-time S]
#
# Makes benches/baseline/.venv (Python 3.11 if there is one) with the pinned NumPy and
# SciPy, builds mirage (`cargo build --release`; set MIRAGE=/path/to/mirage to use a
# binary as it is), and runs compare.py, which prints the table. Arguments go to
# compare.py (see its --help).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)

venv="$here/.venv"
if [ ! -x "$venv/bin/python" ]; then
    py=${PYTHON:-$(command -v python3.11 || command -v python3)}
    "$py" -m venv "$venv"
fi
# Install only when requirements.txt changed since the last install.
if ! cmp -s "$here/requirements.txt" "$venv/.installed-requirements.txt"; then
    "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
    cp "$here/requirements.txt" "$venv/.installed-requirements.txt"
fi

if [ -z "${MIRAGE:-}" ]; then
    (cd "$root" && cargo build --release --quiet)
    MIRAGE="$root/target/release/mirage"
fi

# One core for both sides: mirage runs with --threads 1; keep NumPy's BLAS to one thread.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
echo "start: $(uptime)"
exec "$venv/bin/python" "$here/compare.py" --mirage "$MIRAGE" "$@"
