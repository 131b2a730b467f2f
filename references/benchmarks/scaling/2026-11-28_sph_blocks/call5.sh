#!/bin/bash
# Call 5 (4 x H200): the dam break and the dominoes at four GPUs again, c64 first in each round
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
for r in 1 2 3; do
  for w in c64 base; do run D4_${w}_r$r dambreak-weak 4 $w -; done
  for w in c64 base; do run T4_${w}_r$r topple-weak 4 $w -; done
done
find $R -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' -o -name '*.csv' | xargs rm -f
tar czf $OUT/rec.tgz -C $OUT rec
rm -rf $OUT/rec
