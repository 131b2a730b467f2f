#!/bin/bash
# Its wrappers (dev_w$w.sh) exported QDEMSPH_EXP_BLOCK3=$w QDEMSPH_EXP_BLOCK2=$w (exp_block_hook.patch) and exec-ed the pack's qdemsph.
# Block-size experiment: the capped kernels (SPH density/force MinBlocks<3>, contact narrow MinBlocks<2>)
set -u
export PKDIR=$PWD/build-pack-blk
R=$OUT/rec; mkdir -p $R
nvidia-smi -L > $R/gpus.txt; nproc >> $R/gpus.txt
export LD_LIBRARY_PATH=$PKDIR/lib
run() { # name sweep ranks wrapper gpu extra...
  local name=$1 sweep=$2 n=$3 w=$4 gpu=$5; shift 5
  local env=""; [ "$gpu" != "-" ] && env="CUDA_VISIBLE_DEVICES=$gpu"
  env $env QDEMSPH_REVISION="d94fa87+exp-block-$w" python3 scaling/run.py $sweep --backend cuda --ranks $n \
    --qdemsph $PWD/dev_w$w.sh --out $R/$name "$@" > $R/$name.log 2>&1
  echo "$name rc=$? $(python3 -c "import json,glob;d=json.load(open(glob.glob('$R/$name/*.json')[0]));print(round(d['step_s']*1e3,4), round(d['phases_max_per_step'].get('sph',0)*1e3,4))" 2>&1)"
}
NG=$(nvidia-smi -L | wc -l)
echo "GPUs $NG"
for r in 1 2 3; do
  g=$(( (r-1) % NG ))
  for w in 256 128 64; do
    run D1_b${w}_r$r dambreak-weak 1 $w $g --keep
    [ $NG -ge 2 ] && run D2_b${w}_r$r dambreak-weak 2 $w -
  done
done
# bitwise: fluid.csv of the one-GPU runs
for w in 128 64; do
  a=$(ls $R/D1_b256_r1/runs/*/fluid.csv 2>/dev/null | head -1); b=$(ls $R/D1_b${w}_r1/runs/*/fluid.csv 2>/dev/null | head -1)
  echo "cmp 256 vs $w: $(cmp $a $b && echo identical)"
done
for r in 1 2; do
  g=$(( (r-1) % NG ))
  for w in 256 128; do
    run T1_b${w}_r$r topple-weak 1 $w $g
    [ $NG -ge 2 ] && run T2_b${w}_r$r topple-weak 2 $w -
    run C1_b${w}_r$r cubes-weak 1 $w $g
  done
done
find $R -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' | xargs rm -f
tar czf $OUT/rec.tgz --exclude='*.csv' -C $OUT rec
rm -rf $OUT/rec
