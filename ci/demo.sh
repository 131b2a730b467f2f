#!/usr/bin/env bash
# `make run`: the demo scene end to end, then pictures of it.
# Usage: ci/demo.sh BUILD_DIR
set -euo pipefail
build=${1:-build}
out=$build/demo
"$build/bin/qdemsph" info verification/demos/cantilever_release.yaml
"$build/bin/qdemsph" run verification/demos/cantilever_release.yaml --out "$out"
/usr/bin/python3 verification/tools/plot_run.py "$out"
echo
echo "Open $out/probes.png and $out/snapshots.png; load $out/fields.xdmf in ParaView."
