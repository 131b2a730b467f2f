#!/usr/bin/env bash
# Unit tests under AddressSanitizer + UndefinedBehaviorSanitizer (CPU backend only).
#
#   ci/sanitize.sh [GTEST_FILTER]
#
# Configures the `sanitize` preset of CMakePresets.json (Debug at -O1, QDEMSPH_SANITIZE=ON,
# QDEMSPH_CUDA=OFF, build folder build-sanitize/), builds only qdemsph_tests and runs them.
# Any ASan/UBSan/LeakSanitizer report fails the run (halt_on_error, exit code != 0).
# GTEST_FILTER (or $QDEMSPH_SANITIZE_FILTER) chooses the tests; default: all of them.
# Measured on the 2-core development machine (shared, load 6-10), all 96 tests: 355 s at
# -O1, 1,565 s at -O0 (the five long physics tests, 100-period energy runs, log decrement,
# refinement ladder, 0.9 x dt, two-body impact, took 1,445 s of those). ASan's recommended
# -O1 keeps every check and makes the whole set fit CI's budget.
# JOBS (default 2) is the build parallelism. Prints the time of each phase.
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=${JOBS:-2}
FILTER=${1:-${QDEMSPH_SANITIZE_FILTER:-*}}
t0=$(date +%s)
cmake --preset sanitize >/dev/null
t1=$(date +%s)
cmake --build --preset sanitize --target qdemsph_tests -j "$JOBS"
t2=$(date +%s)
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
# Leaks allocated inside Debian's libgmsh 4.8 are gmsh's (see solver/fuzz/lsan.supp).
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/solver/fuzz/lsan.supp:print_suppressions=0}
# One OpenMP thread: on a shared 2-core machine two threads were measured 6-9x slower.
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
set +e +o pipefail
build-sanitize/bin/qdemsph_tests --gtest_filter="$FILTER" 2>&1 |
  grep -vE '^\[ RUN|^no CUDA device|test_cuda.cpp:[0-9]+: Skipped'
rc=${PIPESTATUS[0]}
set -e -o pipefail
t3=$(date +%s)
echo "sanitize: configure $((t1 - t0)) s, build $((t2 - t1)) s, tests $((t3 - t2)) s" \
     "(filter '$FILTER'), exit $rc"
exit $rc
