#!/usr/bin/env bash
# One whole GPU session (../shared/DEVICE.md): unpack (or build), CUDA unit tests on the GPU,
# GPU-vs-CPU comparison on scenes (element-only, contact, SPH), compute-sanitizer memcheck on
# small scenes, the long-tier 27-cube stack on the GPU, benchmarks (contact, SPH, element step;
# GPU and CPU with every core), then a table printed last. Records go to OUTDIR, flat, at most
# 8 files (what a device call brings back):
#   session.log        everything printed           unit_cuda.json   gtest results of Cuda.*
#   bench_gpu.json / bench_cpu.json   qdemsph_bench records (element + integration step)
#   contact_bench.json ci/gpu/contact_bench.py (GPU and CPU runs)
#   sph_bench.json     scaling/sph_bench.py (GPU and CPU runs) + the largest size by memory
#   stack27.json       ci/gpu/stack_run.py: the 27-cube stack for 1 s on the GPU
#   session.json       all of it collected by ci/gpu/table.py (machine included)
#
#   ci/gpu_session.sh OUTDIR [PACK]
# PACK (made by ci/gpu/pack.sh on a build machine: bin/, lib/ and a copy of the scripts and
# scenes used here) is used when it holds bin/qdemsph; by default the folder this script's
# ci/ sits in, else build-cuda-pack. Otherwise the script builds into build-gpu with cmake.
# SESSION_BUDGET_S (default 540) bounds the wall time: later steps shrink or are skipped once
# it is spent (each step says so). Optional, each minutes: SESSION_LARGEST=1 adds the element
# benchmark's largest size, STACK_CPU=1 the 27-cube stack on the CPU too, SPH_LARGE=N an SPH
# run of N particles (5 steps) on the GPU, SPH_PROFILE=1 an Nsight Compute table of the SPH
# step's kernels at 1 M particles.
set -uo pipefail
export PATH=$PATH:/usr/local/cuda/bin
OUT=${1:?usage: ci/gpu_session.sh OUTDIR [PACK]}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
if [ -n "${2:-}" ]; then
  PACK=$2
elif [ -x "$ROOT/bin/qdemsph" ]; then
  PACK=$ROOT
else
  PACK=$ROOT/build-cuda-pack
fi
PACK=$(cd "$PACK" 2>/dev/null && pwd || echo "$PACK")
BUDGET=${SESSION_BUDGET_S:-540}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
LOG=$OUT/session.log
WORK=$(mktemp -d)
T0=$(date +%s)
exec > >(tee -a "$LOG") 2>&1
export PYTHONUNBUFFERED=1
left() { echo $((BUDGET - ($(date +%s) - T0))); }
# A step's time limit: at most $1 s and at most what is left less $2 s (default 20), >= 10 s.
tmo() { local t=$(( $(left) - ${2:-20} )); [ "$t" -gt "$1" ] && t=$1; [ "$t" -lt 10 ] && t=10; echo $t; }
step() { echo; echo "=== [$(($(date +%s) - T0)) s] $*"; }
skip() { echo "SKIPPED $* (budget: $(left) s left)"; }

step "machine"
NCPU=$(nproc)
GPU=$(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>/dev/null | head -1)
GPU_FREE=$(nvidia-smi --query-gpu=memory.free --format=csv,noheader,nounits 2>/dev/null | head -1)
CPU=$(grep -m1 "model name" /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
echo "GPU: $GPU (free $GPU_FREE MiB)"; echo "CPU: $CPU x $NCPU"; uname -r
echo "compute-sanitizer: $(command -v compute-sanitizer || echo none); nsys: $(command -v nsys || echo none)"
python3 - "$WORK/machine.json" "$GPU" "$CPU" "$NCPU" "${GPU_FREE:-0}" <<'PY'
import json, sys, datetime
json.dump({"gpu": sys.argv[2], "cpu": sys.argv[3], "cpu_threads": int(sys.argv[4]),
           "gpu_free_bytes": int(sys.argv[5] or 0) * 1048576,
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
# The unit tests read solver/tests/data at the absolute path of the build's checkout: point it
# at the pack's copy when that path is missing here.
if [ -f "$PACK/test_data_dir" ]; then
  DATA=$(cat "$PACK/test_data_dir")
  if [ ! -e "$DATA" ] && [ -d "$PACK/solver/tests/data" ]; then
    mkdir -p "$(dirname "$DATA")" "$(dirname "$(dirname "$DATA")")/fuzz"
    ln -s "$PACK/solver/tests/data" "$DATA"
    [ -d "$PACK/solver/fuzz/crashes" ] && ln -s "$PACK/solver/fuzz/crashes" "$(dirname "$(dirname "$DATA")")/fuzz/crashes"
    echo "test data: $DATA -> $PACK/solver/tests/data"
  fi
fi

step "unit tests on the GPU (Cuda.*)"
timeout 300 "$BIN/qdemsph_tests" --gtest_filter='Cuda*' --gtest_output="json:$OUT/unit_cuda.json"
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
compare contact_stack8 verification/cases/contact_stack/scene_8.yaml run.end_time=0.05 output.probes_every=0.005
# That stack starts with every gap exactly at D_DEM, so it magnifies round-off: its sensitivity,
# measured on the CPU alone by shifting one cube by 1e-12 m, is the yardstick for the line above.
cpu_perturbed() {  # name scene set-for-the-second-run [overrides...]
  local name=$1 scene=$2 pert=$3; shift 3
  local sets=()
  for s in "$@"; do sets+=(--set "$s"); done
  timeout 120 "$BIN/qdemsph" run "$ROOT/$scene" -q -b cpu -o "$WORK/$name-cuda" "${sets[@]}" --set "$pert"
  echo "run $name cpu-perturbed rc=$?"
  echo "COMPARE $(python3 "$ROOT/ci/gpu/compare_runs.py" "$name" "$WORK/contact_stack8-cpu" "$WORK/$name-cuda")"
}
cpu_perturbed contact_stack8_cpu_1e-12 verification/cases/contact_stack/scene_8.yaml \
  "bodies.0.mesh.origin=[1e-12,0,0.01]" run.end_time=0.05 output.probes_every=0.005
compare contact_impact verification/cases/contact_impact/scene.yaml
compare contact_sliding verification/cases/contact_sliding/scene_plane.yaml run.end_time=0.05 output.probes_every=0.005
compare sph_dam_break verification/cases/sph_dam_break/scene_mm.yaml run.end_time=0.02 output.fields_every=0.02
if [ "$(left)" -gt 420 ]; then
  compare cantilever_static verification/cases/cantilever_exact/scene_box.yaml
  compare cantilever_preload solver/tests/data/scenes/good/cantilever.yaml run.end_time=0.01 output.fields_every=0
else
  skip "cantilever static/preload comparisons"
fi

step "compute-sanitizer memcheck (small scenes)"
if command -v compute-sanitizer >/dev/null; then
  for sc in "beam ci/gpu/beam_dynamic.yaml bodies.0.mesh.cells=[8,2,2] run.end_time=0.001" \
            "contact verification/cases/contact_stack/scene_8.yaml run.end_time=0.004 output.probes_every=0.002" \
            "sph verification/cases/sph_dam_break/scene_mm.yaml run.end_time=0.0005 output.fields_every=0.0005"; do
    set -- $sc
    name=$1 scene=$2; shift 2
    sets=(); for s in "$@"; do sets+=(--set "$s"); done
    timeout 150 compute-sanitizer --tool memcheck --error-exitcode 99 --print-limit 20 \
      "$BIN/qdemsph" run "$ROOT/$scene" -q -b cuda -o "$WORK/mc-$name" "${sets[@]}" >"$WORK/mc-$name.log" 2>&1
    rc=$?
    tail -4 "$WORK/mc-$name.log"
    echo "MEMCHECK $name rc=$rc steps=$(python3 -c "import json; print(json.load(open('$WORK/mc-$name/summary.json'))['steps'])" 2>/dev/null) $(grep -m1 'ERROR SUMMARY' "$WORK/mc-$name.log")"
  done
  timeout 150 compute-sanitizer --tool memcheck --error-exitcode 99 --print-limit 20 \
    "$BIN/qdemsph_tests" --gtest_filter='Cuda*:-*Relaxation*:*1000*:*Contact*:*Sph*' >"$WORK/mc-unit.log" 2>&1
  rc=$?
  tail -3 "$WORK/mc-unit.log"
  echo "MEMCHECK unit_cuda rc=$rc $(grep -m1 'ERROR SUMMARY' "$WORK/mc-unit.log")"
else
  echo "MEMCHECK none rc=127 compute-sanitizer not found"
fi

step "27-cube stack (verification/cases/contact_stack/scene_27.yaml) for 1 s on the GPU"
STACK_END=1.0
[ "$(left)" -lt 300 ] && STACK_END=0.3 && echo "budget: running to t = $STACK_END s only"
timeout $(tmo 240 90) "$BIN/qdemsph" run "$ROOT/verification/cases/contact_stack/scene_27.yaml" \
  -q -b cuda -o "$WORK/stack27" --set run.end_time=$STACK_END
echo "run stack27 cuda rc=$?"
python3 "$ROOT/ci/gpu/stack_run.py" "$WORK/stack27" "$OUT/stack27.json"
if [ "${STACK_CPU:-0}" = 1 ] && [ "$(left)" -gt 330 ]; then
  echo "the same on the CPU ($NCPU threads), for comparison"
  timeout $(tmo 200 130) "$BIN/qdemsph" run "$ROOT/verification/cases/contact_stack/scene_27.yaml" \
    -q -b cpu -o "$WORK/stack27cpu" --set run.end_time=$STACK_END
  echo "run stack27 cpu rc=$?"
  python3 "$ROOT/ci/gpu/stack_run.py" "$WORK/stack27cpu" "$WORK/stack27cpu.json" | sed 's/^STACK27/STACK27_CPU/'
  python3 - "$OUT/stack27.json" "$WORK/stack27cpu.json" <<'PY'
import json, sys
g = json.load(open(sys.argv[1])); c = json.load(open(sys.argv[2]))
c.pop("series", None)
g["cpu_run"] = c
json.dump(g, open(sys.argv[1], "w"), indent=1)
PY
fi

step "benchmarks: contact throughput (GPU, then CPU with $NCPU threads)"
for n in 20 200; do  # 20 steps: the CPU's horizon; 200: more touches, the steady state
  timeout 150 python3 "$ROOT/ci/gpu/contact_bench.py" "$BIN/qdemsph" --backend cuda --grids 3,6 --steps $n \
    --json "$OUT/contact_bench.json"
  echo "BENCH_CONTACT_GPU steps=$n rc=$?"
done
if [ "$(left)" -gt 200 ]; then
  timeout 120 python3 "$ROOT/ci/gpu/contact_bench.py" "$BIN/qdemsph" --backend cpu --grids 3,6 --steps 20 \
    --json "$OUT/contact_bench.json"
  echo "BENCH_CONTACT_CPU rc=$?"
else
  skip "contact benchmark on the CPU"
fi

step "benchmarks: SPH step (GPU 1 M and 10 M particles, then CPU)"
timeout 200 python3 "$ROOT/scaling/sph_bench.py" --qdemsph "$BIN/qdemsph" --backend cuda --particles 1e6,1e7 \
  --steps 100 --json "$WORK/sph_gpu.json"
echo "BENCH_SPH_GPU rc=$?"
if [ "$(left)" -gt 150 ]; then
  OMP_NUM_THREADS=$NCPU timeout 100 python3 "$ROOT/scaling/sph_bench.py" --qdemsph "$BIN/qdemsph" --backend cpu \
    --particles 1e6 --steps 10 --json "$WORK/sph_cpu.json"
  echo "BENCH_SPH_CPU rc=$?"
else
  skip "SPH benchmark on the CPU"
fi
if [ "${SPH_LARGE:-}" != "" ] && [ "$(left)" -gt 220 ]; then
  timeout 150 python3 "$ROOT/scaling/sph_bench.py" --qdemsph "$BIN/qdemsph" --backend cuda --particles "$SPH_LARGE" \
    --steps 5 --json "$WORK/sph_gpu_large.json"
  echo "BENCH_SPH_LARGE rc=$?"
fi
python3 "$ROOT/ci/gpu/sph_records.py" "$WORK" "$OUT/sph_bench.json"
if [ "${SPH_PROFILE:-0}" = 1 ] && command -v ncu >/dev/null && [ "$(left)" -gt 120 ]; then
  # Nsight Compute over one SPH step at 1 M particles (after the set-up and 20 steps): the time
  # and DRAM traffic of each kernel, the table in session.log.
  timeout 100 python3 "$ROOT/scaling/sph_bench.py" --qdemsph "$BIN/qdemsph" --backend cuda --particles 1e6 \
    --steps 25 --wrap "ncu --clock-control none --launch-skip ${SPH_PROFILE_SKIP:-500} --launch-count 40 \
    --metrics gpu__time_duration.sum,dram__bytes_read.sum,dram__bytes_write.sum,launch__registers_per_thread,sm__warps_active.avg.pct_of_peak_sustained_active,l1tex__t_sector_hit_rate.pct --log-file $WORK/ncu_sph.txt" \
    >/dev/null 2>&1
  echo "SPH_PROFILE rc=$?"
  python3 "$ROOT/ci/gpu/ncu_table.py" "$WORK/ncu_sph.txt"
fi

step "benchmarks: element step (GPU, then CPU with $NCPU threads)"
LARGEST=
[ "${SESSION_LARGEST:-0}" = 1 ] && [ "$(left)" -gt 240 ] && LARGEST=--largest
if [ "$(left)" -gt 60 ]; then
  timeout $(tmo 120 30) "$BIN/qdemsph_bench" --backend cuda --tets 1e6,1e7 $LARGEST \
    --json "$OUT/bench_gpu.json"
  echo "BENCH_GPU rc=$?"
else
  skip "element benchmark on the GPU"
fi
if [ "$(left)" -gt 40 ]; then
  OMP_NUM_THREADS=$NCPU OMP_PROC_BIND=close timeout $(tmo 120 20) \
    "$BIN/qdemsph_bench" --backend cpu --tets 1e6,1e7 --json "$OUT/bench_cpu.json"
  echo "BENCH_CPU rc=$?"
else
  skip "element benchmark on the CPU"
fi

if [ "$(left)" -gt 60 ]; then
  step "all unit tests (gmsh-dependent ones excluded: the GPU machines have no gmsh)"
  timeout $(tmo 120 15) "$BIN/qdemsph_tests" --gtest_brief=1 \
    --gtest_filter='-GmshIo*:Shogi*:*Gmsh*:PatchTest*:Contact.VertexOnSharedEdge*' >"$WORK/unit_all.log" 2>&1
  rc=$?
  tail -15 "$WORK/unit_all.log"
  echo "UNIT_ALL rc=$rc $(grep -E '^\[  (PASSED|FAILED)  \]' "$WORK/unit_all.log" | tr '\n' ' ')"
else
  skip "all unit tests"
fi

step "table"
python3 "$ROOT/ci/gpu/table.py" "$OUT" "$WORK"
rm -rf "$WORK"
