#!/usr/bin/env bash
# CI's fuzz smoke: builds the eight targets in one cargo call (nightly,
# libFuzzer's coverage instrumentation, no sanitizer, the flags `cargo fuzz
# build --sanitizer none` uses, so that CI needs no `cargo install cargo-fuzz`),
# seeds fresh corpora from problems/, and runs each target for a few seconds.
# A crash fails the script (libFuzzer exits non-zero and leaves the input in
# fuzz/artifacts/TARGET/). Usage: fuzz/smoke.sh [SECONDS_PER_TARGET] (default 10).
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-10}
targets=(problem scene fit_result air structured sounding geo photo)
triple=$(rustc +nightly -vV | sed -n 's/^host: //p')
export CARGO_TARGET_DIR=${FUZZ_TARGET_DIR:-$PWD/target}
# --target keeps the instrumentation out of build scripts and proc macros.
RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing \
-Cllvm-args=-simplifycfg-branch-fold-threshold=0 -Cdebug-assertions -Coverflow-checks" \
    cargo +nightly build --release --target "$triple" --bins
./seed.sh >/dev/null
mkdir -p artifacts
for t in "${targets[@]}"; do
    mkdir -p "artifacts/$t"
    echo "-- fuzz $t for ${secs}s"
    # A copy of the seeds, so that a smoke run never grows the corpus.
    work=$(mktemp -d)
    cp -r "corpus/$t/." "$work/"
    log="$work.log"
    if ! "$CARGO_TARGET_DIR/$triple/release/$t" -max_total_time="$secs" -timeout=10 \
        -rss_limit_mb=2048 -artifact_prefix="artifacts/$t/" -print_final_stats=1 "$work" >"$log" 2>&1; then
        tail -n 40 "$log"
        echo "FUZZ TARGET $t FAILED: the input is in fuzz/artifacts/$t/"
        exit 1
    fi
    grep -E '^stat::number_of_executed_units|^#[0-9]+ +DONE' "$log" || true
    rm -f "$log"
    rm -rf "$work"
done
