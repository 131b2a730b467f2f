#!/usr/bin/env bash
# Regenerate every YADE reference under references/yade/results/ (called by `make references`).
# Runs one YADE process at a time, single-threaded, headless (`yade -n -x`). About 130 min of
# one core in all (more wall time on a loaded machine); the chains are most of it. YADE's
# stderr (with the benign "do_intersect ... Unhandled switch case:0" warnings of yade
# 2023.02a) goes to $LOGDIR.
# Usage: references/yade/run_all.sh [--quick]   (--quick: sliding cases only)
set -euo pipefail
cd "$(dirname "$0")"
OUT=results
LOGDIR=${LOGDIR:-$(mktemp -d /tmp/yade_refs.XXXXXX)}
PY=/usr/bin/python3
mkdir -p "$OUT"
command -v yade >/dev/null || { echo "yade not found: run ci/install-deps.sh" >&2; exit 2; }

run() {  # run <log name> <script> <args...>
  local name=$1; shift
  local t0=$SECONDS
  yade -n -x "$@" --out "$OUT" >"$LOGDIR/$name.log" 2>&1 \
    || { echo "FAILED: $* (log $LOGDIR/$name.log)" >&2; exit 1; }
  grep -E '^(SLIDING|SHOGI|LATERAL)' "$LOGDIR/$name.log" | cut -c1-240 || true
  echo "  [$name: $((SECONDS - t0)) s]"
}

# Cube sliding (section 4): base, dt/2, 4x stiffness (with dt/2), and the live-check case.
run sliding         sliding.py --mu 0.5 --v0 3.0 --dt 1e-5 --young 1e8
run sliding_halfdt  sliding.py --mu 0.5 --v0 3.0 --dt 5e-6 --young 1e8 --tag _halfdt
run sliding_stiff4  sliding.py --mu 0.5 --v0 3.0 --dt 5e-6 --young 4e8 --tag _stiff4
run sliding_live    sliding.py --mu 0.5 --v0 1.0 --dt 1e-5 --young 1e8 --tail 0.05 --tag _live
[[ "${1:-}" == "--quick" ]] && { $PY convergence.py "$OUT"; exit 0; }

# Two pieces (point-face), mu 0.1 and 0.5: base, dt/2, 4x stiffness (with dt/2).
for mu in 0.1 0.5; do
  run two_mu$mu         shogi_two.py --mu $mu --dt 1e-5 --young 1e8
  run two_mu${mu}_half  shogi_two.py --mu $mu --dt 5e-6 --young 1e8 --tag _halfdt
  run two_mu${mu}_stiff shogi_two.py --mu $mu --dt 5e-6 --young 4e8 --tag _stiff4
done

# The same at a pitch of 30 mm (0.9375 x height), the spacing of
# verification/cases/contact_shogi/scene_pair.yaml: base and 4x stiffness.
for mu in 0.1 0.5; do
  run two30_mu$mu       shogi_two.py --mu $mu --dt 1e-5 --young 1e8 --pitch 0.9375 --tag _pitch30mm
  run two30_mu${mu}_st  shogi_two.py --mu $mu --dt 5e-6 --young 4e8 --pitch 0.9375 --tag _pitch30mm_stiff4
done

# One piece onto two (edge-edge), mu 0.1 and 0.5: base and 4x stiffness (with dt/2).
for mu in 0.1 0.5; do
  run one_onto_two_mu$mu        shogi_one_onto_two.py --mu $mu --dt 1e-5 --young 1e8
  run one_onto_two_mu${mu}_st   shogi_one_onto_two.py --mu $mu --dt 5e-6 --young 4e8 --tag _stiff4
done

# A piece leaning against a fixed block slides down it (the ladder problem: the chain's sliding
# contacts between leaning pieces), mu 0.1 / 0.3 / 0.5, from the chain's young 1e7 up to 6.4e9
# (dt ~ 1/sqrt(young)), and dt/2 at 1e8 for mu 0.5; 2-100 s each.
for mu in 0.1 0.3 0.5; do
  run lean_mu${mu}_soft10  shogi_leaning.py --mu $mu --dt 2e-5 --young 1e7 --tag _soft10
  run lean_mu${mu}         shogi_leaning.py --mu $mu --dt 1e-5 --young 1e8
  run lean_mu${mu}_stiff4  shogi_leaning.py --mu $mu --dt 5e-6 --young 4e8 --tag _stiff4
  run lean_mu${mu}_stiff16 shogi_leaning.py --mu $mu --dt 2.5e-6 --young 1.6e9 --tag _stiff16
  run lean_mu${mu}_stiff64 shogi_leaning.py --mu $mu --dt 1.25e-6 --young 6.4e9 --tag _stiff64
done
run lean_mu0.5_halfdt shogi_leaning.py --mu 0.5 --dt 5e-6 --young 1e8 --tag _halfdt

# 40-piece chain (softer contact, young 1e7, to afford 95k steps x ~80 contacts), and two
# 20-piece variants compared over pieces 5..18: 4x stiffness (its start needs a stronger push,
# omega0 12 rad/s: with 5 rad/s the first piece only leans on the second at young 4e7), and a
# coarser step (2 x dt, conservative for the step-size spread).
run chain40        shogi_chain.py --n 40 --mu 0.5 --dt 2e-5 --young 1e7
run chain20_stiff4 shogi_chain.py --n 20 --mu 0.5 --dt 2e-5 --young 4e7 --omega0 12 --tag _stiff4
run chain20_dt2x   shogi_chain.py --n 20 --mu 0.5 --dt 4e-5 --young 1e7 --tag _dt2x
# 16x stiffness (young 1.6e8, dt 1e-5), the same push as the 4x run and as qdemsph's chain
# (verification/cases/yade_shogi_chain): does the front keep slowing with stiffer contact?
run chain20_stiff16 shogi_chain.py --n 20 --mu 0.5 --dt 1e-5 --young 1.6e8 --omega0 12 --tag _stiff16
# Friction 0.3 at the dt2x run's settings: how much the front speeds up in YADE (qdemsph: +37 %
# from mu 0.5 to a piece-piece mu 0.3, references/benchmarks/gpu/2026-11-25_h100_chain.json).
run chain20_mu03   shogi_chain.py --n 20 --mu 0.3 --dt 4e-5 --young 1e7 --tag _mu03_dt2x
# The same friction change at 4 x and 16 x young (the stiff4 / stiff16 runs' settings): the
# leaning-piece case (shogi_leaning) loses most of its friction effect at young 1e7.
run chain20_mu03_stiff4  shogi_chain.py --n 20 --mu 0.3 --dt 2e-5 --young 4e7 --omega0 12 --tag _mu03_stiff4
run chain20_mu03_stiff16 shogi_chain.py --n 20 --mu 0.3 --dt 1e-5 --young 1.6e8 --omega0 12 --tag _mu03_stiff16
# Stiffest chains (issue 5: does the front keep slowing toward the rigid-body chain's 0.30 m/s,
# verification/cases/yade_shogi_chain/rigid_chain.py?): 160 x and 640 x young, dt scaled as
# 1/sqrt(young) from the 16x run, push 20 rad/s as the undamped rigid chain (12 stalls there);
# the 16x run again at that push separates push from stiffness. 4, 13 and 24 min of one core.
run chain20_stiff16_w20 shogi_chain.py --n 20 --mu 0.5 --dt 1e-5 --young 1.6e8 --omega0 20 --tag _stiff16_w20
run chain20_stiff160 shogi_chain.py --n 20 --mu 0.5 --dt 3.16e-6 --young 1.6e9 --omega0 20 --tag _stiff160
run chain20_stiff640 shogi_chain.py --n 20 --mu 0.5 --dt 1.58e-6 --young 6.4e9 --omega0 20 --tag _stiff640
# Issue 5, is the 22-26 % gap to the rigid chain friction? (README "Frictionless chain"):
# (1) the stiff160 run without friction; --no-lazy because a frictionless floor lets a hit piece
# slide into the spot where the lazy insertion then puts the next one (the lazy run blew up
# at 0.26 s); 1.5 s: no front forms (one piece falls). 14 min of one core.
run chain20_mu0_stiff160 shogi_chain.py --n 20 --mu 0 --dt 3.16e-6 --young 1.6e9 --omega0 20 --tend 1.5 --no-lazy --tag _mu0_stiff160_nolazy
# (2) the tangential spring's sideways mode is unstable at the chain's (young, dt) pairs from 4e7
# on (shogi_lateral_check.py, 20 s): the stiff160 run at half the step, where it is stable. 26 min.
run lateral_check shogi_lateral_check.py
run chain20_stiff160_halfdt shogi_chain.py --n 20 --mu 0.5 --dt 1.58e-6 --young 1.6e9 --omega0 20 --tag _stiff160_halfdt

$PY convergence.py "$OUT"
echo "logs in $LOGDIR"
