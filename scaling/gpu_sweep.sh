#!/usr/bin/env bash
# Scaling sweeps on a GPU machine in one call (../shared/DEVICE.md): weak-scaling runs of the
# three cases on CPU ranks (1, 2, 4, ... up to the cores: 16 on the H100 host, 32 on the
# two-H200 host) and on 1 vs 2 GPUs (one rank per GPU), the load balancer against a static
# partition (sliding block), interconnect probes, then a table. Records go to OUTDIR (flat):
#   records/*.json  one per run (scaling/run.py)     machine.json  GPUs, CPU, topology
#   probes.json     MPI ping-pong, host<->device copies, two GPUs' device-memory exchange
#                   (CUDA-aware MPI or not; CUDA IPC peer copies): the model's network parameters
#   sweep.log       everything printed               report.md     tables (scaling/report.py)
#
#   scaling/gpu_sweep.sh OUTDIR [PACK]
# PACK (default build-cuda-mpi-pack): made on a build machine by `PACK_MPI=1 ci/gpu/pack.sh`
# (CUDA + MPI build); carried to the GPU machine. SWEEP_BUDGET_S (default 540) bounds the
# whole call: the parts run in order of importance, each with a share of what is left, and
# a part whose next run would not fit is cut short (the record says which ran).
# SWEEP_PARTS (default all) picks parts: cubes-gpu cubes-cpu cubes-copies dambreak-gpu
# dambreak-cpu topple-gpu topple-cpu topple-copies balance-cpu balance-gpu balance-sph probes
# (*-copies: N independent one-rank runs at once, the node's own slowdown, run.py --launcher
# copies; balance-sph: the dam break in a closed tank, balanced against static, fluid-only).
set -uo pipefail
export PATH=$PATH:/usr/local/cuda/bin
OUT=${1:?usage: scaling/gpu_sweep.sh OUTDIR [PACK]}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PACK=${2:-$ROOT/build-cuda-mpi-pack}
BUDGET=${SWEEP_BUDGET_S:-540}
PARTS=${SWEEP_PARTS:-all}
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
cd "$ROOT" || exit 2
WORK=$(mktemp -d)
T0=$(date +%s)
exec > >(tee -a "$OUT/sweep.log") 2>&1
left() { echo $((BUDGET - ($(date +%s) - T0))); }
step() { echo; echo "=== [$(($(date +%s) - T0)) s] $*"; }
want() { [ "$PARTS" = all ] || [[ " $PARTS " == *" $1 "* ]]; }
export PMIX_MCA_pcompress_base_silence_warning=1

step "machine"
NCPU=$(nproc)
NGPU=$(nvidia-smi -L 2>/dev/null | grep -c '^GPU' || true)
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>/dev/null
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2) x $NCPU, GPUs: $NGPU"
nvidia-smi topo -m 2>/dev/null | head -6
mpirun --version 2>/dev/null | head -1

step "binary"
if [ -x "$PACK/bin/qdemsph" ]; then
  export QDEMSPH=$PACK/bin/qdemsph
  export LD_LIBRARY_PATH=$PACK/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  [ -f "$PACK/REVISION" ] && export QDEMSPH_REVISION=$(cat "$PACK/REVISION")
else
  echo "no $PACK/bin/qdemsph: make it with PACK_MPI=1 ci/gpu/pack.sh and carry it"; exit 2
fi
"$QDEMSPH" version
ldd "$QDEMSPH" | grep -E "not found|libmpi" || true
python3 - "$OUT/machine.json" <<'PY'
import json, sys
sys.path.insert(0, "scaling")
import run
json.dump(run.machine_facts(__import__("os").environ["QDEMSPH"]), open(sys.argv[1], "w"), indent=1)
PY

# Rank counts: powers of two up to the cores (CPU ranks) and up to the GPUs.
CPU_RANKS=1; r=2; while [ $r -le "$NCPU" ]; do CPU_RANKS="$CPU_RANKS,$r"; r=$((r * 2)); done
GPU_RANKS=""; [ "$NGPU" -ge 1 ] && GPU_RANKS=1; [ "$NGPU" -ge 2 ] && GPU_RANKS="1,2"
echo "CPU ranks: $CPU_RANKS   GPU ranks: ${GPU_RANKS:-none}"

step "is the binary distributed? (2 CPU ranks, tiny scene)"
DIST=0
python3 -c "import sys; sys.path.insert(0, 'scaling'); import scenes; s, _ = scenes.cube_block(4, cells=2); \
s['run']['end_time'] = 0.002; print(scenes.dump(s))" > "$WORK/probe.yaml"
ROOTARG=""; [ "$(id -u)" = 0 ] && ROOTARG=--allow-run-as-root
timeout 120 mpirun $ROOTARG -np 2 --oversubscribe -x OMP_NUM_THREADS=1 "$QDEMSPH" run "$WORK/probe.yaml" \
  -q -o "$WORK/probe" >"$WORK/probe.log" 2>&1
echo "probe rc=$?"; tail -3 "$WORK/probe.log"
if python3 -c "import json,sys; s=json.load(open('$WORK/probe/summary.json')); sys.exit(0 if (s.get('parallel') or {}).get('ranks')==2 else 1)" 2>/dev/null; then
  DIST=1; echo "distributed stepper: yes"
else
  echo "distributed stepper: NO (summary.json has no parallel.ranks = 2): only the 1-rank runs are measured"
  CPU_RANKS=1; GPU_RANKS=${GPU_RANKS:+1}
fi

# part NAME SHARE_OF_LEFT SWEEP ARGS...: run.py with a budget of min(left - 30, share x left).
part() {
  local name=$1 share=$2 sweep=$3; shift 3
  want "$name" || return 0
  local l=$(left); [ "$l" -lt 40 ] && { echo "skip $name: budget spent"; return 0; }
  local b=$(python3 -c "print(int(min($l - 30, $share * $l)))")
  step "$name: $sweep $* (budget $b s)"
  python3 scaling/run.py "$sweep" "$@" --out "$OUT" --work "$WORK/runs" --budget "$b" --timeout "$b" \
    --qdemsph "$QDEMSPH"
  echo "PART $name rc=$?"
}

if [ -n "$GPU_RANKS" ]; then part cubes-gpu 0.12 cubes-weak --backend cuda --ranks "$GPU_RANKS"; fi
part cubes-cpu 0.35 cubes-weak --backend cpu --ranks "$CPU_RANKS"
part cubes-copies 0.3 cubes-weak --backend cpu --ranks "$CPU_RANKS" --launcher copies
if [ -n "$GPU_RANKS" ]; then part dambreak-gpu 0.08 dambreak-weak --backend cuda --ranks "$GPU_RANKS"; fi
part dambreak-cpu 0.3 dambreak-weak --backend cpu --ranks "$CPU_RANKS"
if [ -n "$GPU_RANKS" ]; then part topple-gpu 0.2 topple-weak --backend cuda --ranks "$GPU_RANKS"; fi
part topple-cpu 0.40 topple-weak --backend cpu --ranks "$CPU_RANKS"
part topple-copies 0.4 topple-weak --backend cpu --ranks "$CPU_RANKS" --launcher copies
if [ "$DIST" = 1 ]; then
  BAL=4; [ "$NCPU" -ge 16 ] && BAL=4,8
  part balance-cpu 0.6 slide-balance --backend cpu --ranks "$BAL" --variants balanced,static
  [ "$NGPU" -ge 2 ] && part balance-gpu 0.9 slide-balance --backend cuda --ranks 2 --variants balanced,static
  part balance-sph 0.9 dambreak-balance --backend cpu --ranks "$BAL" --variants balanced,static
fi

if want probes && [ "$(left)" -gt 30 ]; then
  step "probes: MPI ping-pong (2 ranks, host memory), host<->device copies, device-memory exchange (2 GPUs)"
  {
    echo "["
    if command -v mpicc >/dev/null && mpicc -O2 -o "$WORK/pingpong" scaling/probes/pingpong.c 2>/dev/null; then
      timeout 60 mpirun $ROOTARG -np 2 --map-by core --bind-to core "$WORK/pingpong" || echo '{"probe": "mpi_pingpong_host", "error": "failed"}'
    else
      echo '{"probe": "mpi_pingpong_host", "error": "no mpicc"}'
    fi
    echo ","
    if [ "$NGPU" -ge 1 ] && command -v nvcc >/dev/null && nvcc -O2 -o "$WORK/copybw" scaling/probes/copybw.cu 2>/dev/null; then
      timeout 60 "$WORK/copybw" || echo '{"probe": "cuda_copy", "error": "failed"}'
    else
      echo '{"probe": "cuda_copy", "error": "no GPU or nvcc"}'
    fi
    echo ","
    if [ "$NGPU" -ge 2 ] && nvcc -O2 $(mpicc --showme:compile) -o "$WORK/devicecomm" scaling/probes/devicecomm.cu \
        $(mpicc --showme:link) 2>/dev/null; then
      timeout 90 mpirun $ROOTARG -np 2 "$WORK/devicecomm" || echo '{"probe": "device_comm", "error": "failed"}'
    else
      echo '{"probe": "device_comm", "error": "fewer than 2 GPUs, or no nvcc / mpicc"}'
    fi
    echo "]"
  } > "$OUT/probes.json"
  cat "$OUT/probes.json"
fi

step "table"
python3 scaling/report.py "$OUT/records" --out "$WORK/report" --no-prediction >/dev/null && cp "$WORK/report/report.md" "$OUT/report.md"
cat "$OUT/report.md"
ls "$OUT/records" | wc -l | xargs echo "records:"
rm -rf "$WORK"
