#!/usr/bin/env bash
# A coupled fluid-structure demo end to end: scene info, run, pictures.
# Usage: ci/demo_fsi.sh BUILD_DIR [SCENE] [qdemsph run options...]
#   SCENE: dambreak_cubes (default) or debris_flow (verification/demos/SCENE.yaml), or a path
#   to a scene file. Further arguments go to `qdemsph run`, e.g. --backend cuda, or a
#   reduced-resolution check on a CPU: --set fluid.spacing=0.02 --set run.threads=1
# Output: BUILD_DIR/demo_SCENE/ or $DEMO_OUT when set (frames.png, forces.png, fields.xdmf,
# fluid.xdmf, probes.csv, fluid.csv, summary.json).
set -euo pipefail
build=${1:-build}
scene=${2:-dambreak_cubes}
shift $(($# < 2 ? $# : 2))
[[ -f $scene ]] || scene=verification/demos/$scene.yaml
name=$(basename "$scene" .yaml)
out=${DEMO_OUT:-$build/demo_$name}
info_args=()  # `qdemsph info` takes the --set overrides only
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do
  case ${args[i]} in
    --set) info_args+=(--set "${args[i + 1]:-}"); i=$((i + 1)) ;;
    --set=*) info_args+=("${args[i]}") ;;
  esac
done
"$build/bin/qdemsph" info "$scene" "${info_args[@]}"
"$build/bin/qdemsph" run "$scene" --out "$out" "$@"
/usr/bin/python3 verification/tools/plot_fsi.py "$out"
echo
echo "Open $out/frames.png and $out/forces.png; load $out/fluid.xdmf and $out/fields.xdmf in ParaView."
