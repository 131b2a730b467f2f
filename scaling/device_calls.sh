# Helpers for a records folder's calls.sh (references/benchmarks/scaling/*/calls.sh): one device
# call compares packs (build folders carried as build-pack-<pack>, ci/gpu/pack.sh) at the
# scaling presets. Sourced in the repository root of a device machine; records under
# $OUT/rec, returned by finish_call as $OUT/rec.tgz (no h5, xdmf, vtu or csv).
set -u
R=$OUT/rec
mkdir -p $R
nvidia-smi -L >$R/gpus.txt
nproc >>$R/gpus.txt
NG=$(nvidia-smi -L | wc -l)
declare -A REV  # wrapper -> the revision its records carry

# wrapper NAME PACK REVISION [VAR=VALUE ...]: dev_w_NAME.sh runs the pack's qdemsph with the
# given variables exported (an experiment hook's settings).
wrapper() {
  REV[$1]=$3
  {
    echo '#!/bin/bash'
    [ $# -ge 4 ] && echo "export ${*:4}"
    echo "export LD_LIBRARY_PATH=$PWD/build-pack-$2/lib"
    echo "exec $PWD/build-pack-$2/bin/qdemsph \"\$@\""
  } >$PWD/dev_w_$1.sh
  chmod +x $PWD/dev_w_$1.sh
}

# run NAME SWEEP RANKS WRAPPER GPU|- [run.py arguments]: one record; prints its step (ms) and
# each rank's SPH phase (ms a step).
run() {
  local name=$1 sweep=$2 n=$3 w=$4 gpu=$5
  shift 5
  local env=""
  [ "$gpu" != "-" ] && env="CUDA_VISIBLE_DEVICES=$gpu"
  env $env QDEMSPH_REVISION="${REV[$w]}" python3 scaling/run.py $sweep --backend cuda --ranks $n \
    --qdemsph $PWD/dev_w_$w.sh --out $R/$name "$@" >$R/$name.log 2>&1
  echo "$name rc=$? $(python3 -c "
import json, glob
d = json.load(open(glob.glob('$R/$name/records/*.json')[0]))
p = (d.get('parallel') or {}).get('phases_by_rank') or []
print(round(d['step_s'] * 1e3, 4), [round((q.get('sph') or 0) / d['steps'] * 1e3, 3) for q in p])" 2>&1 | tail -1)"
}

# d_rounds FROM TO "COUNTS" WRAPPER...: rounds FROM..TO of the weak dam break at each GPU count
# of COUNTS ("1 2 4"; one GPU: GPU (round - 1) mod GPUs), the wrappers in the order given;
# d12_rounds FROM TO WRAPPER...: at one GPU and two.
d_rounds() {
  local from=$1 to=$2 counts=$3
  shift 3
  for r in $(seq $from $to); do
    for w in "$@"; do
      for n in $counts; do
        run D${n}_${w}_r$r dambreak-weak $n $w $([ $n = 1 ] && echo $(((r - 1) % NG)) || echo -)
      done
    done
  done
}
d12_rounds() { d_rounds "$1" "$2" "1 2" "${@:3}"; }

# same_fluid N A B: round 1 of the N-GPU dam break with wrappers A and B, outputs kept, and
# whether their fluid.csv are the same bytes.
same_fluid() {
  local n=$1 a=$2 b=$3
  for w in $a $b; do run D${n}_${w}_r1 dambreak-weak $n $w - --keep; done
  echo "cmp $n-GPU fluid.csv $a vs $b: $(cmp $R/D${n}_${a}_r1/runs/*/fluid.csv \
    $R/D${n}_${b}_r1/runs/*/fluid.csv && echo identical)"
}

# gpu_tests PACK LOCAL_FILTER [MPI_FILTER]: the pack's unit tests on one GPU, the distributed
# ones on two.
gpu_tests() {
  local mpi_filter=${3:-'Distributed.GpuRanks*:Distributed.SlackRebuilds*:HaloPlan.*'}
  (
    cd build-pack-$1 && export LD_LIBRARY_PATH=$PWD/lib
    ./bin/qdemsph_tests --gtest_filter="$2" >$R/gputests_local.log 2>&1
    echo "local tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_local.log | tail -2 | tr '\n' ' ')"
    mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests \
      --gtest_filter="$mpi_filter" >$R/gputests_mpi.log 2>&1
    echo "mpi tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_mpi.log | tail -2 | tr '\n' ' ')"
  )
  grep -a "cuda-vs-cpu" $R/gputests_local.log
}

# finish_call: the records packed for the trip back.
finish_call() {
  find $R \( -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' -o -name '*.csv' \) -delete
  tar czf $OUT/rec.tgz -C $OUT rec
  rm -rf $R
}
