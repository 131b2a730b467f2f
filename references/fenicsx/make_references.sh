#!/usr/bin/env bash
# Regenerate the stored FEniCSx references (`make references`).
# Usage: make_references.sh [QDEMSPH_BINARY] [make_references.py options, see --help]
# The binary (default $QDEMSPH, else build/bin/qdemsph) exports the meshes. Serial and
# single-threaded; about 2-4 minutes and 3 GB of memory on 2 cores for the cantilevers, then
# under a minute for the elastic gate under still water (gate_static.py, 2-D, no binary needed).
set -euo pipefail
cd "$(dirname "$0")/../.."
args=()
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then
  args+=(--qdemsph "$1")
  shift
fi
/usr/bin/python3 references/fenicsx/make_references.py "${args[@]}" "$@"
case " $* " in *" -h "* | *" --help "*) exit 0 ;; esac
exec /usr/bin/python3 references/fenicsx/gate_static.py
