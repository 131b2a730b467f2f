#!/bin/bash
# Submits one Slurm job per rank count of a GPU sweep (one rank per GPU).
#   scaling/slurm/submit.sh SWEEP OUTDIR [GPUS_PER_NODE=4] [CPUS_PER_TASK=8] [RANKS="1 2 4 ... 512"]
# Afterwards: /usr/bin/python3 scaling/report.py OUTDIR/records
set -euo pipefail
SWEEP=${1:?usage: submit.sh SWEEP OUTDIR [GPUS_PER_NODE] [CPUS_PER_TASK] [RANKS]}
OUT=${2:?}
GPN=${3:-4}
CPT=${4:-8}
RANKS=${5:-"1 2 4 8 16 32 64 128 256 512"}
for n in $RANKS; do
  nodes=$(( (n + GPN - 1) / GPN ))
  per=$(( n < GPN ? n : GPN ))
  sbatch -N "$nodes" --ntasks="$n" --ntasks-per-node="$per" --gpus-per-node="$per" --cpus-per-task="$CPT" \
    --job-name="qdemsph-$SWEEP-$n" "$(dirname "$0")/weak_gpu.sbatch" "$SWEEP" "$OUT"
done
