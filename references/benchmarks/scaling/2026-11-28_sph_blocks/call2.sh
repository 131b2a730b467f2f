#!/bin/bash
# Call 2: GPU tests of e4836c0 (b64), then the SPH and contact block sizes: b64 against blk (d94fa87 + env hook) at 256 / 32
set -u
R=$OUT/rec; mkdir -p $R
nvidia-smi -L > $R/gpus.txt; nproc >> $R/gpus.txt
mkw() { # wrapper name pack b3 b2
  cat > $PWD/dev_w_$1.sh <<W
#!/bin/bash
export QDEMSPH_EXP_BLOCK3=$3 QDEMSPH_EXP_BLOCK2=$4
export LD_LIBRARY_PATH=$PWD/build-pack-$2/lib
exec $PWD/build-pack-$2/bin/qdemsph "\$@"
W
  chmod +x $PWD/dev_w_$1.sh
}
mkw base blk 256 256; mkw b64 b64 256 256; mkw x32 blk 32 256; mkw c128 blk 256 128; mkw c64 blk 256 64
( cd build-pack-b64 && export LD_LIBRARY_PATH=$PWD/lib
  ./bin/qdemsph_tests --gtest_filter='Cuda*:Sph*:Fluid*:Contact*:Memory*:LocalModel*' > $R/gputests_local.log 2>&1; echo "local tests rc=$? $(grep -E '^\[  (PASSED|FAILED)' $R/gputests_local.log | tr '\n' ' ')"
  mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests --gtest_filter='Distributed.GpuRanks*:Distributed.SlackRebuilds*:HaloPlan.*' > $R/gputests_mpi.log 2>&1; echo "mpi tests rc=$? $(grep -E '^\[  (PASSED|FAILED)' $R/gputests_mpi.log | tr '\n' ' ')" )
grep "cuda-vs-cpu" $R/gputests_local.log | grep -i sph
run() { # name sweep ranks wrapper gpu
  local name=$1 sweep=$2 n=$3 w=$4 gpu=$5; shift 5
  local env=""; [ "$gpu" != "-" ] && env="CUDA_VISIBLE_DEVICES=$gpu"
  local rev=e4836c0; [ $w != b64 ] && rev="d94fa87+exp-block-$w"
  env $env QDEMSPH_REVISION="$rev" python3 scaling/run.py $sweep --backend cuda --ranks $n \
    --qdemsph $PWD/dev_w_$w.sh --out $R/$name "$@" > $R/$name.log 2>&1
  echo "$name rc=$? $(python3 -c "import json,glob;d=json.load(open(glob.glob('$R/$name/records/*.json')[0]));print(round(d['step_s']*1e3,4), [round(p.get('sph',0)/d['steps']*1e3,3) for p in d['parallel']['phases_by_rank']] if d.get('parallel') and d['parallel'].get('phases_by_rank') else '')" 2>&1 | tail -1)"
}
NG=$(nvidia-smi -L | wc -l)
for r in 1 2 3 4; do
  g=$(( (r-1) % NG ))
  for w in base b64 x32; do
    run D1_${w}_r$r dambreak-weak 1 $w $g
    [ $NG -ge 2 ] && run D2_${w}_r$r dambreak-weak 2 $w -
  done
done
for r in 1 2 3; do
  g=$(( (r-1) % NG ))
  for w in base c128 c64; do run C1_${w}_r$r cubes-weak 1 $w $g; done
done
for r in 1 2; do
  g=$(( (r-1) % NG ))
  for w in base c128 c64; do
    run T1_${w}_r$r topple-weak 1 $w $g
    [ $NG -ge 2 ] && run T2_${w}_r$r topple-weak 2 $w -
  done
done
find $R -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' | xargs rm -f
tar czf $OUT/rec.tgz --exclude='*.csv' -C $OUT rec
rm -rf $OUT/rec
