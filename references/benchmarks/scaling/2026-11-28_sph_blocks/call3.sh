#!/bin/bash
# Call 3: GPU tests of 92d07b5 (c64: SPH passes and contact narrow phase in blocks of 64), the
# contact results against d94fa87 (blk pack, hook inert), then interleaved rounds of all three weak cases
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
( cd build-pack-c64 && export LD_LIBRARY_PATH=$PWD/lib
  ./bin/qdemsph_tests --gtest_filter='Cuda*:Contact*:LocalModel*:Sph*' > $R/gputests_local.log 2>&1; echo "local tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_local.log | tail -2 | tr '\n' ' ')"
  mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests --gtest_filter='Distributed.GpuRanks*:Distributed.SlackRebuilds*:HaloPlan.*' > $R/gputests_mpi.log 2>&1; echo "mpi tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_mpi.log | tail -2 | tr '\n' ' ')" )
grep -a "cuda-vs-cpu" $R/gputests_local.log | grep -ai contact | head -20
run() { # name sweep ranks wrapper gpu
  local name=$1 sweep=$2 n=$3 w=$4 gpu=$5; shift 5
  local env=""; [ "$gpu" != "-" ] && env="CUDA_VISIBLE_DEVICES=$gpu"
  local rev=92d07b5; [ $w != c64 ] && rev="d94fa87+exp-block-inert"
  env $env QDEMSPH_REVISION="$rev" python3 scaling/run.py $sweep --backend cuda --ranks $n \
    --qdemsph $PWD/dev_w_$w.sh --out $R/$name "$@" > $R/$name.log 2>&1
  echo "$name rc=$? $(python3 -c "import json,glob;d=json.load(open(glob.glob('$R/$name/records/*.json')[0]));print(round(d['step_s']*1e3,4), [round((p.get('sph') or 0)/d['steps']*1e3,3) for p in d['parallel']['phases_by_rank']] if d.get('parallel') and d['parallel'].get('phases_by_rank') else '')" 2>&1 | tail -1)"
}
NG=$(nvidia-smi -L | wc -l)
for s in C:cubes-weak T:topple-weak; do
  k=${s%%:*}; sw=${s#*:}
  for w in base c64; do run ${k}1_${w}_r1 $sw 1 $w 0 --keep; done
  python3 -c "
import json,glob
a,b=[json.load(open(glob.glob('$R/${k}1_'+w+'_r1/runs/*/summary.json')[0])) for w in ('base','c64')]
print('$k summary energies+contact', 'identical' if (a['contact'],a['energies'])==(b['contact'],b['energies']) else 'DIFFER', a['energies'], b['energies'])
" 2>&1 | tail -1
  [ $NG -ge 2 ] && for w in base c64; do run ${k}2_${w}_r1 $sw 2 $w -; done
done
for r in 2 3; do
  g=$(( (r-1) % NG ))
  for s in C:cubes-weak T:topple-weak; do
    k=${s%%:*}; sw=${s#*:}
    for w in base c64; do
      run ${k}1_${w}_r$r $sw 1 $w $g
      [ $NG -ge 2 ] && run ${k}2_${w}_r$r $sw 2 $w -
    done
  done
done
for r in 1 2; do
  g=$(( (r-1) % NG ))
  for w in base c64; do
    run D1_${w}_r$r dambreak-weak 1 $w $g
    [ $NG -ge 2 ] && run D2_${w}_r$r dambreak-weak 2 $w -
  done
done
find $R -name '*.h5' -o -name '*.xdmf' -o -name '*.vtu' -o -name '*.csv' | xargs rm -f
tar czf $OUT/rec.tgz -C $OUT rec
rm -rf $OUT/rec
