#!/bin/bash
# Call 4 (4 x H200): 92d07b5 (c64) against d94fa87 (blk pack, hook inert), the three weak cases at 1, 2 and 4 GPUs
set -u
R=$OUT/rec; mkdir -p $R
nvidia-smi -L > $R/gpus.txt; nproc >> $R/gpus.txt
mkw() { # wrapper name pack
  cat > $PWD/dev_w_$1.sh <<W
#!/bin/bash
export LD_LIBRARY_PATH=$PWD/build-pack-$2/lib
exec $PWD/build-pack-$2/bin/qdemsph "\$@"
W
  chmod +x $PWD/dev_w_$1.sh
}
mkw base blk; mkw c64 c64
run() { # name sweep ranks wrapper gpu
  local name=$1 sweep=$2 n=$3 w=$4 gpu=$5; shift 5
  local env=""; [ "$gpu" != "-" ] && env="CUDA_VISIBLE_DEVICES=$gpu"
  local rev=92d07b5; [ $w != c64 ] && rev="d94fa87+exp-block-inert"
  env $env QDEMSPH_REVISION="$rev" python3 scaling/run.py $sweep --backend cuda --ranks $n \
    --qdemsph $PWD/dev_w_$w.sh --out $R/$name "$@" > $R/$name.log 2>&1
  echo "$name rc=$? $(python3 -c "import json,glob;d=json.load(open(glob.glob('$R/$name/records/*.json')[0]));print(round(d['step_s']*1e3,4), [round((p.get('sph') or 0)/d['steps']*1e3,3) for p in d['parallel']['phases_by_rank']] if d.get('parallel') and d['parallel'].get('phases_by_rank') else '')" 2>&1 | tail -1)"
}
NG=$(nvidia-smi -L | wc -l)
for r in 1 2; do
  for s in D:dambreak-weak C:cubes-weak T:topple-weak; do
    k=${s%%:*}; sw=${s#*:}
    for w in base c64; do
      if [ $w = base ]; then g=$(( (2*r-2) % NG )); else g=$(( (2*r-1) % NG )); fi
      run ${k}1_${w}_r$r $sw 1 $w $g
      run ${k}2_${w}_r$r $sw 2 $w -
      [ $NG -ge 4 ] && run ${k}4_${w}_r$r $sw 4 $w -
    done
  done
done
find $R -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' -o -name '*.csv' | xargs rm -f
tar czf $OUT/rec.tgz -C $OUT rec
rm -rf $OUT/rec
