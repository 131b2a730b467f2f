#!/usr/bin/env bash
# Builds the libFuzzer targets of solver/fuzz/ with Debian's clang-14
# (-fsanitize=fuzzer,address,undefined) and runs each for a bounded time.
#
#   ci/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default 60 s; targets: all)
#
# Targets: fuzz_scene (parse_scene on arbitrary YAML text), fuzz_scene_overrides (--set
# overrides on a valid scene), fuzz_gmsh (qdemsph's .msh reader on arbitrary bytes; no libgmsh).
# Seed corpora:
# solver/tests/data/scenes/{good,bad}/*.yaml and solver/fuzz/corpus/<target>/ (checked-in
# seeds); the grown corpus is kept in build-fuzz/corpus/<target>/ between runs (CI may cache
# it). Fails (exit 1) on a crash, a sanitizer report (ASan, UBSan, LeakSanitizer), an input
# slower than 10 s (hang) or more than 2 GB RSS; the reproducer is left in build-fuzz/artifacts/.
# Reproduce one: build-fuzz/fuzz_scene build-fuzz/artifacts/fuzz_scene/crash-<sha1>
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET=${1:-60}
shift || true
TARGETS=("$@")
[[ ${#TARGETS[@]} -gt 0 ]] || TARGETS=(fuzz_scene fuzz_scene_overrides fuzz_gmsh)
CXX=${FUZZ_CXX:-clang++-14}
OUT=${FUZZ_BUILD:-build-fuzz}
mkdir -p "$OUT/obj" "$OUT/artifacts" "$OUT/corpus"

# Compile only what the targets need (the parser, the mesh reader), instrumented.
FLAGS=(-std=c++20 -g -O1 -fno-omit-frame-pointer -fsanitize=address,undefined
       -fno-sanitize-recover=undefined -Isolver)
declare -A SRC=([scene]=solver/io/scene_yaml.cpp [gmsh]=solver/mesh/gmsh_io.cpp
                [msh_reader]=solver/mesh/msh_reader.cpp)
t0=$(date +%s)
for k in "${!SRC[@]}"; do
  o="$OUT/obj/$k.o"
  if [[ ! -f $o || ${SRC[$k]} -nt $o || ci/fuzz.sh -nt $o || -n $(find solver/io solver/core solver/mesh -name '*.hpp' -newer "$o" -print -quit) ]]; then
    "$CXX" "${FLAGS[@]}" -fsanitize=fuzzer-no-link -c "${SRC[$k]}" -o "$o"
  fi
done
declare -A OBJS=([fuzz_scene]="$OUT/obj/scene.o" [fuzz_scene_overrides]="$OUT/obj/scene.o"
                 [fuzz_gmsh]="$OUT/obj/gmsh.o $OUT/obj/msh_reader.o")
declare -A LIBS=([fuzz_scene]="-lyaml-cpp" [fuzz_scene_overrides]="-lyaml-cpp" [fuzz_gmsh]="")
for t in "${TARGETS[@]}"; do
  [[ -n ${OBJS[$t]:-} ]] || { echo "fuzz.sh: unknown target '$t'" >&2; exit 2; }
  # shellcheck disable=SC2086
  "$CXX" "${FLAGS[@]}" -fsanitize=fuzzer "solver/fuzz/$t.cpp" ${OBJS[$t]} ${LIBS[$t]} -o "$OUT/$t"
done
t1=$(date +%s)
echo "fuzz.sh: built ${TARGETS[*]} in $((t1 - t0)) s"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/solver/fuzz/lsan.supp:print_suppressions=0}
rc=0
for t in "${TARGETS[@]}"; do
  corpus="$OUT/corpus/$t"
  art="$OUT/artifacts/$t"
  mkdir -p "$corpus" "$art"
  seeds=()
  [[ -d solver/fuzz/corpus/$t ]] && seeds+=("solver/fuzz/corpus/$t")
  if [[ $t == fuzz_scene ]]; then
    seeds+=(solver/tests/data/scenes/good solver/tests/data/scenes/bad)
  fi
  # The reproducers of past findings run first, every time.
  [[ $t == fuzz_gmsh ]] && seeds+=(solver/fuzz/crashes)
  dict=()
  [[ -f solver/fuzz/$t.dict ]] && dict=(-dict="solver/fuzz/$t.dict")
  s0=$(date +%s)
  set +e
  "$OUT/$t" "$corpus" "${seeds[@]}" "${dict[@]}" -max_total_time="$SECONDS_PER_TARGET" \
      -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$art/" >"$OUT/$t.log" 2>&1
  trc=$?
  set -e
  s1=$(date +%s)
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$OUT/$t.log" | grep -o '[0-9]*$' || true)
  cov=$(grep -o 'cov: [0-9]*' "$OUT/$t.log" | tail -1 || true)
  rss=$(grep -o 'stat::peak_rss_mb: *[0-9]*' "$OUT/$t.log" | grep -o '[0-9]*$' || true)
  if [[ $trc -ne 0 ]]; then
    echo "fuzz.sh: $t FAILED (exit $trc) after $((s1 - s0)) s; log $OUT/$t.log, reproducer in $art/:"
    grep -E 'ERROR|SUMMARY|runtime error|escaped|Test unit written' "$OUT/$t.log" | head -20
    rc=1
  else
    echo "fuzz.sh: $t ok: ${execs:-?} inputs in $((s1 - s0)) s, $cov, peak RSS ${rss:-?} MB," \
         "corpus $(ls "$corpus" | wc -l) files"
  fi
done
exit $rc
