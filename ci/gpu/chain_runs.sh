#!/usr/bin/env bash
# The 40-piece shogi chain (verification/cases/yade_shogi_chain) and 20-piece variants on one
# GPU, all at once (MPS when it starts): mesh refinement, 4 x stiffer bodies, friction 0.3
# between pieces (c20_mu03) or everywhere, as YADE's mu 0.3 run (c20_mu03all), no contact
# damping (restitution 1, as YADE's undamped law: c20_e1*). Two stages, since the GPU machines
# have no gmsh:
#   ci/gpu/chain_runs.sh prepare DIR [NAME ...]    here: premeshed scenes (ci/gpu/premesh.py),
#                                                  all variants or the NAMEs given
#   DIR/../chain_runs.sh run DIR PACK OUT [LIMIT_S] there: runs, then one .tgz per variant in OUT
#   ci/gpu/chain_runs.sh analyse OUT RECORD.json   here: fall times and front speeds, one record
# (records of 2026-11-25: references/benchmarks/gpu/2026-11-25_h100_chain.json).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
CASE=$ROOT/verification/cases/yade_shogi_chain
# name  pieces  mesh_size  end_time  run-time overrides
VARIANTS="c40 40 0.006 3.6 -
c20_E4 20 0.006 1.9 materials.boxwood.E=2e7
c20 20 0.006 1.9 -
c20_mu03 20 0.006 1.9 contact.mu=0.3
c20_mu03all 20 0.006 1.9 contact.mu=0.3 walls.0.mu=0.3
c20_e1 20 0.006 1.9 contact.restitution=1.0
c20_e1_mu03all 20 0.006 1.9 contact.restitution=1.0 contact.mu=0.3 walls.0.mu=0.3
f20_4 20 0.004 1.9 -
f20_3 20 0.003 1.9 -"
case ${1:?prepare, run or analyse} in
prepare)
  DIR=${2:?DIR}; shift 2; mkdir -p "$DIR"; cp "$0" "$DIR/../chain_runs.sh"
  while read -r name n h end sets; do
    [ $# -eq 0 ] || [[ " $* " == *" $name "* ]] || continue
    /usr/bin/python3 "$CASE/make_yade_chain.py" --n "$n" --mesh-size "$h" --end-time "$end" --out "$DIR/$name.yaml"
    /usr/bin/python3 "$ROOT/ci/gpu/premesh.py" "$ROOT/build/bin/qdemsph" "$DIR/$name.yaml" "$DIR/$name" >/dev/null
    echo "$sets" >"$DIR/$name/sets"
  done <<<"$VARIANTS" ;;
run)
  DIR=$(cd "${2:?DIR}" && pwd); PACK=$(cd "${3:?PACK}" && pwd); OUT=${4:?OUT}; LIMIT=${5:-540}
  export LD_LIBRARY_PATH=$PACK/lib
  nvidia-cuda-mps-control -d 2>/dev/null || true  # (an error when it already runs)
  pgrep -f nvidia-cuda-mps-control >/dev/null && echo "MPS on" || echo "no MPS"
  for d in "$DIR"/*/; do
    name=$(basename "$d"); sets=(); for s in $(cat "$d/sets"); do [ "$s" = - ] || sets+=(--set "$s"); done
    (cd "$d" && rc=0 && timeout "$LIMIT" "$PACK/bin/qdemsph" run scene.yaml -q -b cuda -o "/tmp/chain/$name" \
       "${sets[@]}" >"/tmp/chain_$name.log" 2>&1 || rc=$?; echo "$name rc=$rc") &
  done
  wait
  for d in "$DIR"/*/; do  # a run stopped by LIMIT has no summary.json: what it wrote comes back
    name=$(basename "$d"); cp "/tmp/chain_$name.log" "/tmp/chain/$name/run.log"
    files=(); for f in probes.csv summary.json fields.h5 run.log; do [ -f "/tmp/chain/$name/$f" ] && files+=("$name/$f"); done
    tar czf "$OUT/$name.tgz" -C /tmp/chain "${files[@]}"
  done ;;
analyse)
  OUT=${2:?OUT}; REC=${3:?RECORD.json}; T=$(mktemp -d)
  for f in "$OUT"/*.tgz; do tar xzf "$f" -C "$T"; done
  /usr/bin/python3 "$CASE/chain_analysis.py" "$T"/* --json "$REC"
  rm -rf "$T" ;;
esac
