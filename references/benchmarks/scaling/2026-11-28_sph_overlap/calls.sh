#!/bin/bash
# The device calls of this folder (README.md), as they ran: `bash calls.sh callN` in the
# repository root of a device machine, with the packs of README's table carried as
# build-pack-<pack>. Records under $OUT/rec, returned as $OUT/rec.tgz (no h5, xdmf, csv).
set -u
R=$OUT/rec
mkdir -p $R
nvidia-smi -L >$R/gpus.txt
nproc >>$R/gpus.txt
NG=$(nvidia-smi -L | wc -l)
declare -A REV  # wrapper -> the revision its records carry

# wrapper NAME PACK REVISION: dev_w_NAME.sh runs the pack's qdemsph.
wrapper() {
  REV[$1]=$3
  {
    echo '#!/bin/bash'
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

# gpu_tests PACK LOCAL_FILTER MPI_FILTER: the pack's unit tests on one GPU, the distributed ones
# on two.
gpu_tests() {
  (
    cd build-pack-$1 && export LD_LIBRARY_PATH=$PWD/lib
    ./bin/qdemsph_tests --gtest_filter="$2" >$R/gputests_local.log 2>&1
    echo "local tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_local.log | tail -2 | tr '\n' ' ')"
    mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests \
      --gtest_filter="$3" >$R/gputests_mpi.log 2>&1
    echo "mpi tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_mpi.log | tail -2 | tr '\n' ' ')"
  )
  grep -a "cuda-vs-cpu" $R/gputests_local.log
}

# The packs: 92d07b5 (c64, the SPH code before); 86eb7d3 (ov: the passes over particles no
# ghost is near run while the pressure refreshes travel, split by a test per particle;
# rejected); 6e657c4 (ol: split by lists made at the sort; rejected, reverted by 14de646);
# f45f64d (tr: the refreshes without the waits for the timers; no gain, reverted by e67e020);
# ce1dc5e (sd: ol with the passes near ghosts on the side stream; landed). The rejected packs'
# records were relabelled "+split-rejected" and "+waits-rejected" after the calls (README).
# Call 4 carried build-pack-fin (e67e020) for its tests only.
packs() {
  wrapper c64 c64 92d07b5
  wrapper ov ov 86eb7d3
  wrapper ol ol 6e657c4
  wrapper tr tr f45f64d
  wrapper sd sd ce1dc5e
}

# Call 1 (2 x H200): ov's tests; the two-GPU fluid.csv of c64 and ov compared; interleaved
# rounds of the dam break at one and two GPUs.
call1() {
  packs
  gpu_tests ov 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for w in c64 ov; do run D2_${w}_r1 dambreak-weak 2 $w - --keep; done
  echo "cmp two-GPU fluid.csv c64 vs ov: $(cmp $R/D2_c64_r1/runs/*/fluid.csv $R/D2_ov_r1/runs/*/fluid.csv && echo identical)"
  for w in c64 ov; do run D1_${w}_r1 dambreak-weak 1 $w 0; done
  for r in 2 3 4; do
    for w in ov c64; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
    done
  done
}

# Call 2 (2 x H200): as call 1, with ol for ov.
call2() {
  packs
  gpu_tests ol 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for w in c64 ol; do run D2_${w}_r1 dambreak-weak 2 $w - --keep; done
  echo "cmp two-GPU fluid.csv c64 vs ol: $(cmp $R/D2_c64_r1/runs/*/fluid.csv $R/D2_ol_r1/runs/*/fluid.csv && echo identical)"
  for w in c64 ol; do run D1_${w}_r1 dambreak-weak 1 $w 0; done
  for r in 2 3 4; do
    for w in c64 ol; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
    done
  done
}

# Call 3 (2 x H200): the tests of tr (f45f64d: the refreshes' waits trimmed, on the reverted
# split); interleaved rounds of the dam break at one and two GPUs, c64 and tr.
call3() {
  packs
  gpu_tests tr 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for r in 1 2 3 4 5; do
    for w in c64 tr; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
    done
  done
}

# Call 4 (2 x H200): the tests of the code that landed (fin: e67e020, 92d07b5's solver and the
# new GPU test of the distributed fluid).
call4() {
  gpu_tests fin 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
}

# Call 5 (2 x H200): sd (ce1dc5e: the split with lists, the passes near ghosts on the side
# stream): its tests, the two-GPU fluid.csv against c64's, interleaved rounds at one and two GPUs.
call5() {
  packs
  gpu_tests sd 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for w in c64 sd; do run D2_${w}_r1 dambreak-weak 2 $w - --keep; done
  echo "cmp two-GPU fluid.csv c64 vs sd: $(cmp $R/D2_c64_r1/runs/*/fluid.csv $R/D2_sd_r1/runs/*/fluid.csv && echo identical)"
  for w in c64 sd; do run D1_${w}_r1 dambreak-weak 1 $w 0; done
  for r in 2 3 4 5; do
    for w in c64 sd; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
    done
  done
}

# Call 6 (4 x H200): the dam break at one, two and four GPUs, c64 and sd interleaved.
call6() {
  packs
  for r in 1 2 3; do
    for w in c64 sd; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
      run D4_${w}_r$r dambreak-weak 4 $w -
    done
  done
}

"$1"
find $R \( -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' -o -name '*.csv' \) -delete
tar czf $OUT/rec.tgz -C $OUT rec
rm -rf $R
