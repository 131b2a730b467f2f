#!/bin/bash
# The six device calls of this folder (README.md), as they ran: `bash calls.sh callN` in the
# repository root of a device machine, with the packs of README's table carried as
# build-pack-<pack>. Records under $OUT/rec, returned as $OUT/rec.tgz (no h5, xdmf, csv).
set -u
R=$OUT/rec
mkdir -p $R
nvidia-smi -L >$R/gpus.txt
nproc >>$R/gpus.txt
NG=$(nvidia-smi -L | wc -l)
declare -A REV  # wrapper -> the revision its records carry

# wrapper NAME PACK REVISION [BLOCK3 BLOCK2]: dev_w_NAME.sh runs the pack's qdemsph, with the
# experiment hook's block sizes exported when given (exp_block_hook.patch; the blk pack only).
wrapper() {
  REV[$1]=$3
  {
    echo '#!/bin/bash'
    [ $# -ge 5 ] && echo "export QDEMSPH_EXP_BLOCK3=$4 QDEMSPH_EXP_BLOCK2=$5"
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

# gpu_tests PACK LOCAL_FILTER: the pack's unit tests on one GPU, the distributed ones on two.
gpu_tests() {
  (
    cd build-pack-$1 && export LD_LIBRARY_PATH=$PWD/lib
    ./bin/qdemsph_tests --gtest_filter="$2" >$R/gputests_local.log 2>&1
    echo "local tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_local.log | tail -2 | tr '\n' ' ')"
    mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests \
      --gtest_filter='Distributed.GpuRanks*:Distributed.SlackRebuilds*:HaloPlan.*' >$R/gputests_mpi.log 2>&1
    echo "mpi tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_mpi.log | tail -2 | tr '\n' ' ')"
  )
  grep -a "cuda-vs-cpu" $R/gputests_local.log
}

# Call 1: both hooks at 256, 128 and 64 threads a block; fluid.csv of the one-GPU runs compared.
call1() {
  for b in 256 128 64; do wrapper b$b blk d94fa87+exp-block-$b $b $b; done
  for r in 1 2 3; do
    for b in 256 128 64; do
      run D1_b${b}_r$r dambreak-weak 1 b$b $(((r - 1) % NG)) --keep
      run D2_b${b}_r$r dambreak-weak 2 b$b -
    done
  done
  for b in 128 64; do
    echo "cmp 256 vs $b: $(cmp $R/D1_b256_r1/runs/*/fluid.csv $R/D1_b${b}_r1/runs/*/fluid.csv && echo identical)"
  done
  for r in 1 2; do
    for b in 256 128; do
      run T1_b${b}_r$r topple-weak 1 b$b $(((r - 1) % NG))
      run T2_b${b}_r$r topple-weak 2 b$b -
      run C1_b${b}_r$r cubes-weak 1 b$b $(((r - 1) % NG))
    done
  done
}

# Call 2: the tests of e4836c0 (b64); the SPH passes at 256 (base), 64 (b64) and 32 (x32); the
# contact kernel at 256, 128 and 64.
call2() {
  wrapper base blk d94fa87+exp-block-base 256 256
  wrapper b64 b64 e4836c0
  wrapper x32 blk d94fa87+exp-block-x32 32 256
  wrapper c128 blk d94fa87+exp-block-c128 256 128
  wrapper c64 blk d94fa87+exp-block-c64 256 64
  gpu_tests b64 'Cuda*:Sph*:Fluid*:Contact*:Memory*:LocalModel*'
  for r in 1 2 3 4; do
    for w in base b64 x32; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
    done
  done
  for r in 1 2 3; do
    for w in base c128 c64; do run C1_${w}_r$r cubes-weak 1 $w $(((r - 1) % NG)); done
  done
  for r in 1 2; do
    for w in base c128 c64; do
      run T1_${w}_r$r topple-weak 1 $w $(((r - 1) % NG))
      run T2_${w}_r$r topple-weak 2 $w -
    done
  done
}

# Calls 3-5: 92d07b5 (c64) against d94fa87 (the blk pack, its hook unset).
finals() {
  wrapper base blk d94fa87+exp-block-inert
  wrapper c64 c64 92d07b5
}

# Call 3 (2 x H200): the tests of 92d07b5; the cube block's and the dominoes' energies and contact
# counts with both packs; interleaved rounds of the three cases at one and two GPUs.
call3() {
  finals
  gpu_tests c64 'Cuda*:Contact*:LocalModel*:Sph*'
  for s in C:cubes-weak T:topple-weak; do
    k=${s%%:*} sw=${s#*:}
    for w in base c64; do run ${k}1_${w}_r1 $sw 1 $w 0 --keep; done
    python3 -c "
import json, glob
a, b = [json.load(open(glob.glob('$R/${k}1_' + w + '_r1/runs/*/summary.json')[0])) for w in ('base', 'c64')]
same = (a['contact'], a['energies']) == (b['contact'], b['energies'])
print('$k summary energies+contact', 'identical' if same else 'DIFFER', a['energies'], b['energies'])"
    for w in base c64; do run ${k}2_${w}_r1 $sw 2 $w -; done
  done
  for r in 2 3; do
    for s in C:cubes-weak T:topple-weak; do
      k=${s%%:*} sw=${s#*:}
      for w in base c64; do
        run ${k}1_${w}_r$r $sw 1 $w $(((r - 1) % NG))
        run ${k}2_${w}_r$r $sw 2 $w -
      done
    done
  done
  for r in 1 2; do
    for w in base c64; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
    done
  done
}

# Call 4 (4 x H200): the three cases at 1, 2 and 4 GPUs, two rounds.
call4() {
  finals
  for r in 1 2; do
    for s in D:dambreak-weak C:cubes-weak T:topple-weak; do
      k=${s%%:*} sw=${s#*:}
      for w in base c64; do
        if [ $w = base ]; then g=$(((2 * r - 2) % NG)); else g=$(((2 * r - 1) % NG)); fi
        run ${k}1_${w}_r$r $sw 1 $w $g
        run ${k}2_${w}_r$r $sw 2 $w -
        run ${k}4_${w}_r$r $sw 4 $w -
      done
    done
  done
}

# Call 5 (another 4 x H200 host): the dam break and the dominoes at four GPUs, c64 first.
call5() {
  finals
  for r in 1 2 3; do
    for w in c64 base; do run D4_${w}_r$r dambreak-weak 4 $w -; done
    for w in c64 base; do run T4_${w}_r$r topple-weak 4 $w -; done
  done
}

# Call 6 (2 x H200), rejected: the dam break at two GPUs with the fluid's first skin half a kernel
# support (s50: 41a55bb with kFluidSkin = 0.5) against 92d07b5.
call6() {
  wrapper c64 c64 92d07b5
  wrapper s50 s50 41a55bb+fluid-skin-0.5
  run D2_s50_r1 dambreak-weak 2 s50 -
  run D2_c64_r1 dambreak-weak 2 c64 -
  run D2_s50_r2 dambreak-weak 2 s50 -
  run D2_c64_r2 dambreak-weak 2 c64 -
  run D1_s50_r1 dambreak-weak 1 s50 0
  run D2_s50_r3 dambreak-weak 2 s50 -
  run D2_c64_r3 dambreak-weak 2 c64 -
}

"$1"
find $R \( -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' -o -name '*.csv' \) -delete
tar czf $OUT/rec.tgz -C $OUT rec
rm -rf $R
