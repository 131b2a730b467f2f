#!/usr/bin/env bash
# One whole GPU session (../shared/DEVICE.md): build or unpack, CUDA unit tests on the GPU,
# GPU-vs-CPU comparison on scenes, compute-sanitizer memcheck on a small scene, benchmarks
# (GPU and CPU), then a table printed last. Records go to OUTDIR (flat, <= 8 files):
#   session.log  everything printed      unit_cuda.json  gtest results of Cuda.*
#   bench_gpu.json / bench_cpu.json      qdemsph_bench records (see solver/bench/)
#   machine.json GPU, driver, CPU        session.json    all of it collected (ci/gpu/table.py)
#
#   ci/gpu_session.sh OUTDIR [PACK]
# PACK (default build-cuda-pack, made by ci/gpu/pack.sh on a build machine) is used when it
# holds bin/qdemsph; otherwise the script builds into build-gpu with cmake (needs the
# dependencies; GoogleTest and gmsh are optional there). SESSION_BUDGET_S (default 540)
# bounds the wall time: optional steps are skipped once it is spent.
set -uo pipefail
export PATH=$PATH:/usr/local/cuda/bin
OUT=${1:?usage: ci/gpu_session.sh OUTDIR [PACK]}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PACK=${2:-$ROOT/build-cuda-pack}
BUDGET=${SESSION_BUDGET_S:-540}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
LOG=$OUT/session.log
WORK=$(mktemp -d)
T0=$(date +%s)
exec > >(tee -a "$LOG") 2>&1
left() { echo $((BUDGET - ($(date +%s) - T0))); }
step() { echo; echo "=== [$(($(date +%s) - T0)) s] $*"; }

step "machine"
NCPU=$(nproc)
GPU=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>/dev/null | head -1)
CPU=$(grep -m1 "model name" /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
echo "GPU: $GPU"; echo "CPU: $CPU x $NCPU"; uname -r
python3 - "$OUT/machine.json" "$GPU" "$CPU" "$NCPU" <<'PY'
import json, sys, datetime
json.dump({"gpu": sys.argv[2], "cpu": sys.argv[3], "cpu_threads": int(sys.argv[4]),
           "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")},
          open(sys.argv[1], "w"), indent=2)
PY

step "build or unpack"
if [ -x "$PACK/bin/qdemsph" ]; then
  BIN=$PACK/bin
  export LD_LIBRARY_PATH=$PACK/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  echo "using the packed build in $PACK"
else
  cmake -S "$ROOT" -B "$ROOT/build-gpu" -DQDEMSPH_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DCMAKE_BUILD_TYPE=Release && cmake --build "$ROOT/build-gpu" -j "$NCPU" || exit 1
  BIN=$ROOT/build-gpu/bin
fi
"$BIN/qdemsph" version
ldd "$BIN/qdemsph" | grep -i "not found" && echo "WARNING: missing libraries"

step "unit tests on the GPU (Cuda.*)"
timeout 240 "$BIN/qdemsph_tests" --gtest_filter='Cuda*' --gtest_output="json:$OUT/unit_cuda.json"
echo "UNIT_CUDA rc=$?"

step "GPU vs CPU on scenes"
compare() {  # name scene [overrides...]
  local name=$1 scene=$2; shift 2
  local sets=()
  for s in "$@"; do sets+=(--set "$s"); done
  for b in cpu cuda; do
    timeout 120 "$BIN/qdemsph" run "$ROOT/$scene" -q -b $b -o "$WORK/$name-$b" "${sets[@]}"
    echo "run $name $b rc=$?"
  done
  echo "COMPARE $(python3 "$ROOT/ci/gpu/compare_runs.py" "$name" "$WORK/$name-cpu" "$WORK/$name-cuda")"
}
compare beam_dynamic_1000 ci/gpu/beam_dynamic.yaml
[ "$(left)" -gt 300 ] && compare cantilever_static verification/cases/cantilever_exact/scene_box.yaml
[ "$(left)" -gt 280 ] && compare cantilever_preload solver/tests/data/scenes/good/cantilever.yaml \
  run.end_time=0.01 output.fields_every=0

step "compute-sanitizer memcheck (small scenes)"
if command -v compute-sanitizer >/dev/null; then
  for sc in "beam ci/gpu/beam_dynamic.yaml bodies.0.mesh.cells=[8,2,2] run.end_time=0.001" \
            "static verification/cases/cantilever_exact/scene_box.yaml run.static.max_steps=300"; do
    set -- $sc
    name=$1 scene=$2; shift 2
    sets=(); for s in "$@"; do sets+=(--set "$s"); done
    timeout 120 compute-sanitizer --tool memcheck --error-exitcode 99 --print-limit 20 \
      "$BIN/qdemsph" run "$ROOT/$scene" -q -b cuda -o "$WORK/mc-$name" "${sets[@]}" >"$WORK/mc-$name.log" 2>&1
    rc=$?
    tail -5 "$WORK/mc-$name.log"
    echo "MEMCHECK $name rc=$rc $(grep -m1 'ERROR SUMMARY' "$WORK/mc-$name.log")"
  done
  timeout 150 compute-sanitizer --tool memcheck --error-exitcode 99 --print-limit 20 \
    "$BIN/qdemsph_tests" --gtest_filter='Cuda*:-*Relaxation*:*1000*' >"$WORK/mc-unit.log" 2>&1
  rc=$?
  tail -4 "$WORK/mc-unit.log"
  echo "MEMCHECK unit_cuda rc=$rc $(grep -m1 'ERROR SUMMARY' "$WORK/mc-unit.log")"
else
  echo "MEMCHECK none rc=127 compute-sanitizer not found"
fi

step "benchmarks: GPU"
LARGEST=--largest
[ "$(left)" -lt 240 ] && LARGEST=
timeout $(( $(left) > 330 ? 300 : $(left) - 30 )) "$BIN/qdemsph_bench" --backend cuda --tets 1e6,1e7 $LARGEST --json "$OUT/bench_gpu.json"
echo "BENCH_GPU rc=$?"

step "benchmarks: CPU ($NCPU threads)"
if [ "$(left)" -gt 40 ]; then
  OMP_NUM_THREADS=$NCPU OMP_PROC_BIND=close timeout $(( $(left) - 20 )) \
    "$BIN/qdemsph_bench" --backend cpu --tets 1e6,1e7 --json "$OUT/bench_cpu.json"
  echo "BENCH_CPU rc=$?"
fi

if [ "$(left)" -gt 60 ]; then
  step "all unit tests (gmsh-dependent ones excluded: the GPU machines have no gmsh)"
  timeout $(( $(left) - 15 )) "$BIN/qdemsph_tests" --gtest_brief=1 --gtest_filter='-GmshIo*:Shogi*:*Gmsh*' >"$WORK/unit_all.log" 2>&1
  rc=$?
  tail -15 "$WORK/unit_all.log"
  echo "UNIT_ALL rc=$rc $(grep -E '^\[  (PASSED|FAILED)  \]' "$WORK/unit_all.log" | tr '\n' ' ')"
fi

step "table"
python3 "$ROOT/ci/gpu/table.py" "$OUT"
rm -rf "$WORK"
