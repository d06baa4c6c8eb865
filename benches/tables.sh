#!/usr/bin/env bash
# Every performance table of the README, regenerated in one run:
#
#   bash benches/tables.sh [SECTION ...]     (default: all of them, in this order)
#
# Sections (the README section each table belongs to):
#   trace     "Performance": RK4 and Dormand–Prince throughput per medium and path,
#             the cost of one exact Jacobian           (cargo bench --bench trace, table only)
#   fit       "Bundled problems" and "Performance": fit time per bundled problem,
#             one thread                                  (cargo bench --bench fit, table only)
#   render    "Looking through the air": 1280×720 render time per scene, 2 threads
#                                                         (cargo bench --bench render, table only)
#   tradeoff  "Speed against accuracy": mirage --threads 1 tradeoff problems/hot-road.json
#   baseline  "Performance": mirage against the SciPy fit  (benches/baseline/compare.sh)
#   air       "Real air": the Wigner lab's fan against its simulator
#                                                         (benches/peers/wigner/bench.py)
#   grow      "Growing the model": time to grow each example (problems/grow/measure.py)
#   large     "Large inputs": time and peak memory against input size
#                                                         (benches/large_inputs.py)
#
# Each section prints the machine's load average before and after it: the figures
# are wall-clock or CPU times on a machine that may be shared, and the load says how
# much to trust them. The README's figures are what this script printed, with the
# machine and load it printed beside them.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

all=(trace fit render tradeoff baseline air grow large)
sections=("$@")
[ ${#sections[@]} -eq 0 ] && sections=("${all[@]}")
for s in "${sections[@]}"; do
    case " ${all[*]} " in
        *" $s "*) ;;
        *) echo "benches/tables.sh: unknown section '$s' (one of: ${all[*]})" >&2; exit 2 ;;
    esac
done

load() { cut -d' ' -f1-3 /proc/loadavg; }

echo "# mirage performance tables"
echo
echo "- commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet 2>/dev/null || echo ' (with local changes)')"
echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "- CPU: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n1), $(nproc) logical cores$(grep -q avx512f /proc/cpuinfo && echo ', AVX-512')"
echo "- memory: $(awk '/MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo)"
echo "- rustc: $(rustc -V)"

# One release build for every section that runs the binary.
cargo build --release --quiet
mirage="$root/target/release/mirage"

for s in "${sections[@]}"; do
    echo
    echo "## $s"
    echo
    echo "load average before (1, 5, 15 min): $(load)"
    echo
    case $s in
        trace)
            MIRAGE_BENCH_TABLE_ONLY=1 cargo bench --quiet --bench trace 2>/dev/null
            ;;
        fit)
            RAYON_NUM_THREADS=1 MIRAGE_BENCH_TABLE_ONLY=1 cargo bench --quiet --bench fit 2>/dev/null
            ;;
        render)
            RAYON_NUM_THREADS=2 MIRAGE_BENCH_TABLE_ONLY=1 cargo bench --quiet --bench render 2>/dev/null
            ;;
        tradeoff)
            csv=$(mktemp --suffix=.csv)
            "$mirage" --threads 1 tradeoff problems/hot-road.json --csv "$csv" >/dev/null
            python3 - "$csv" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("`mirage --threads 1 tradeoff problems/hot-road.json`\n")
print("| integrator | endpoint error (m) | evaluations / ray | trace, all pairs | fit: parameter error | fit time |")
print("| --- | --- | --- | --- | --- | --- |")
def t(s):
    v = float(s)
    return f"{v * 1e6:.0f} µs" if v < 1e-3 else f"{v * 1e3:.1f} ms" if v < 1 else f"{v:.2f} s"
for r in rows:
    name = ("RK4, %g m" % float(r["setting"])) if r["method"] == "rk4" else ("Dormand–Prince, %g" % float(r["setting"]))
    pe = "%.1e" % float(r["fit_parameter_error"]) if r["fit_parameter_error"] else "–"
    ft = t(r["fit_time_s"]) if r["fit_time_s"] else "–"
    print(f"| {name} | {float(r['endpoint_error_m']):.1e} | {float(r['rhs_per_ray']):.0f} | {t(r['trace_time_s'])} | {pe} | {ft} |")
EOF
            rm -f "$csv"
            ;;
        baseline)
            MIRAGE="$mirage" bash benches/baseline/compare.sh
            ;;
        air)
            python3 benches/peers/wigner/bench.py --reps 10
            ;;
        grow)
            python3 problems/grow/measure.py --mirage "$mirage" --repeat 3
            ;;
        large)
            python3 benches/large_inputs.py --mirage "$mirage"
            ;;
    esac
    echo
    echo "load average after: $(load)"
done
