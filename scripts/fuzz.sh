#!/usr/bin/env bash
# Runs the libFuzzer harnesses of tests/fuzz/ (docs/fuzzing.md) for SECONDS in total, split evenly among the
# harnesses given (default: all), one after the other. Builds them first in BUILD (default build-fuzz, clang++
# with ASan + UBSan, -j1 unless JOBS is set) and the seed corpora (scripts/fuzz-corpus.sh).
# Each run stops at its first crash, leak, sanitizer report, timeout (-timeout=10 s) or out-of-memory
# (-rss_limit_mb=2048); the input is copied to tests/fuzz/regressions/<harness>/ for the replay test
# (tests/test_fuzz_regressions.cpp) and the script exits non-zero. Prints the executions per harness.
#
#   scripts/fuzz.sh SECONDS [harness...]      e.g. scripts/fuzz.sh 3600, scripts/fuzz.sh 180 ply
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
all=(xml obj ply serialized exr png vol vdb optimize_config)
if [ $# -lt 1 ] || ! [[ "$1" =~ ^[0-9]+$ ]]; then
    echo "usage: $0 SECONDS [harness...]   (harnesses: ${all[*]})" >&2
    exit 2
fi
total="$1"; shift
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=("${all[@]}")
for h in "${harnesses[@]}"; do
    [[ " ${all[*]} " == *" $h "* ]] || { echo "fuzz.sh: unknown harness '$h' (expected: ${all[*]})" >&2; exit 2; }
done
per=$((total / ${#harnesses[@]}))
[ "$per" -ge 1 ] || per=1
build="${BUILD:-$root/build-fuzz}"

# Build (incremental): the library and the harnesses, instrumented.
launcher=()
if command -v ccache >/dev/null; then
    export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
mkdir -p "$build/logs"
if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang \
        -DPENUMBRA_FUZZ=ON -DPENUMBRA_BUILD_TESTS=OFF -DPENUMBRA_BUILD_BENCH=OFF -DPENUMBRA_BUILD_APP=OFF \
        -DPENUMBRA_BUILD_PYTHON=OFF "${launcher[@]}" >"$build/logs/configure.log" 2>&1 ||
        { tail -20 "$build/logs/configure.log" >&2; echo "fuzz.sh: configuring $build failed" >&2; exit 2; }
fi
echo "fuzz.sh: building the harnesses in $build (log: $build/logs/build.log)" >&2
cmake --build "$build" -j"${JOBS:-1}" --target $(printf 'fuzz_%s ' "${harnesses[@]}") >"$build/logs/build.log" 2>&1 ||
    { tail -30 "$build/logs/build.log" >&2; echo "fuzz.sh: the build failed" >&2; exit 2; }
"$root/scripts/fuzz-corpus.sh" "$build" >/dev/null

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan_suppressions.txt${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
failed=0
rows=()
for h in "${harnesses[@]}"; do
    artifacts="$build/artifacts/$h"
    rm -rf "$artifacts"
    mkdir -p "$artifacts"
    log="$build/logs/$h.log"
    extra=()
    [ -d "$root/tests/fuzz/seeds/$h" ] && extra+=("$root/tests/fuzz/seeds/$h")
    [ -d "$root/tests/fuzz/regressions/$h" ] && extra+=("$root/tests/fuzz/regressions/$h")
    [ -f "$root/tests/fuzz/$h.dict" ] && extra=(-dict="$root/tests/fuzz/$h.dict" "${extra[@]}")
    echo "fuzz.sh: $h for ${per} s (log: $log)" >&2
    start=$(date +%s)
    status=0
    "$build/fuzz_$h" -max_total_time="$per" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$artifacts/" "$build/corpus/$h" "${extra[@]}" >"$log" 2>&1 || status=$?
    seconds=$(( $(date +%s) - start ))
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    execs="${execs:-?}"
    result=ok
    rm -f "$artifacts"/slow-unit-*  # slower than 10 s but not a timeout: not a failure
    found=$(find "$artifacts" -type f | wc -l)
    if [ "$status" -ne 0 ] || [ "$found" -gt 0 ]; then
        failed=1
        result="FAILED (exit $status; $(grep -m1 -oE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer): [a-z-]+|runtime error: .{0,60}' "$log" || echo see log))"
        mkdir -p "$root/tests/fuzz/regressions/$h"
        for f in "$artifacts"/*; do
            [ -f "$f" ] && cp "$f" "$root/tests/fuzz/regressions/$h/" && echo "fuzz.sh: $h: input saved as tests/fuzz/regressions/$h/$(basename "$f")" >&2
        done
    fi
    rate="?"
    [[ "$execs" =~ ^[0-9]+$ ]] && [ "$seconds" -gt 0 ] && rate=$((execs / seconds))
    rows+=("$(printf '| %-15s | %7s | %12s | %8s | %s |' "$h" "$seconds" "$execs" "$rate" "$result")")
done

printf '| %-15s | %7s | %12s | %8s | %s |\n' harness seconds executions "exec/s" result
printf '|%s|%s|%s|%s|%s|\n' "-----------------" "---------" "--------------" "----------" "--------"
printf '%s\n' "${rows[@]}"
exit "$failed"
