"""Is the tangential spring of YADE's Polyhedra law stable at the chain's (young, dt)?

The start of shogi_chain.py with two pieces (piece 0 tilted 21.5 deg with the push, piece 1
upright, the slab floor; same helpers, so the same set-up) for --tend s, once per setting
(young, dt, poisson). At every step: each interaction's shear force component along y, the
width axis, over its normal force. The chain is planar: nothing pushes along y, so this ratio
should stay at round-off. If the explicit step cannot hold the contact's tangential spring
(ks = young * poisson / 2 N/m) it grows from round-off until it reaches the Coulomb cap (mu):
the sideways force then takes the friction that the in-plane motion would have had.

Outputs <out>/shogi_lateral_check.csv (one row per setting: young, dt, poisson, the maximum
ratio per contact and when the piece-piece ratio first passed 0.01, the tilts at the end) and
its provenance JSON.

Run: yade -n -x shogi_lateral_check.py --out results
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))
import common  # noqa: E402
import shogi_scene as ss  # noqa: E402
import yade_setup as ys  # noqa: E402
from yade import O, PyRunner  # noqa: E402

# (young, dt, poisson): the chain runs' pairs (run_all.sh), shogi_leaning's at 1.6e9 / 6.4e9,
# and two changes of the 1.6e9 chain's: half the step, 2.5 x smaller ks.
SETTINGS = [(1e7, 2e-5, 0.25), (1e7, 4e-5, 0.25), (4e7, 2e-5, 0.25), (1.6e8, 1e-5, 0.25),
            (1.6e9, 3.16e-6, 0.25), (6.4e9, 1.58e-6, 0.25), (1.6e9, 2.5e-6, 0.25),
            (6.4e9, 1.25e-6, 0.25), (1.6e9, 1.58e-6, 0.25), (1.6e9, 3.16e-6, 0.1)]

p = argparse.ArgumentParser(description=__doc__)
p.add_argument("--mu", type=float, default=0.5)
p.add_argument("--omega0", type=float, default=20.0)
p.add_argument("--tilt0", type=float, default=21.5)
p.add_argument("--tend", type=float, default=0.02)
p.add_argument("--out", default="results")
args = ys.parse(p, sys.argv)
size, rho = common.SHOGI_DEFAULT, common.BOXWOOD_DENSITY
h, w, t = common.SHOGI_SIZES[size]
pitch = 0.6 * h


def run(young, dt, poisson):
    O.reset()
    mat = ys.material(young, poisson, args.mu, rho)
    floor = ss.add_floor(mat, -2 * h, 3 * pitch + 2 * h, -w, w)
    a0 = ss.add_piece(mat, 0.0, 0.0, args.tilt0, size, omega0=args.omega0)
    a1 = ss.add_piece(mat, pitch, 0.0, 0.0, size, ss.standing_sink(size, rho, young))
    kind = {frozenset((floor, a0.id)): "floor_p0", frozenset((floor, a1.id)): "floor_p1",
            frozenset((a0.id, a1.id)): "p0_p1"}
    worst = {k: 0.0 for k in kind.values()}
    first = [None]

    def sample():
        for i in O.interactions:
            fn = i.phys.normalForce.norm() if i.isReal else 0.0
            if fn <= 1e-4:
                continue
            k = kind[frozenset((i.id1, i.id2))]
            r = abs(i.phys.shearForce[1]) / fn
            worst[k] = max(worst[k], r)
            if k == "p0_p1" and r > 0.01 and first[0] is None:
                first[0] = O.time

    import builtins
    builtins._lateral_sample = sample
    ys.setup_engines(dt, [PyRunner(command="_lateral_sample()", iterPeriod=1)])
    ys.run_steps(args.tend / dt)
    return [young, dt, poisson, worst["p0_p1"], worst["floor_p0"], worst["floor_p1"],
            first[0] if first[0] is not None else float("nan"), a0.tilt_deg(), a1.tilt_deg()]


wall0 = time.time()
rows = []
for s in SETTINGS:
    rows.append(run(*s))
    print("LATERAL young %g dt %g poisson %g: max |Fs_y|/|Fn| p0-p1 %.3g, floor-p0 %.3g, floor-p1 %.3g; "
          "p0-p1 past 0.01 at %s s; tilts %.2f %.2f deg" % tuple(rows[-1][:6] + [rows[-1][6]] + rows[-1][7:]),
          flush=True)
wall = time.time() - wall0
header = ["young", "dt", "poisson", "max_lat_p0_p1", "max_lat_floor_p0", "max_lat_floor_p1",
          "t_lat_p0_p1_above_0.01", "tilt_0_end", "tilt_1_end"]
os.makedirs(args.out, exist_ok=True)
name = os.path.join(args.out, "shogi_lateral_check")
common.write_csv(name + ".csv", header, rows, fmt="%.6g")
params = {"mu": args.mu, "omega0_rad_per_s": args.omega0, "tilt0_deg": args.tilt0, "tend_s": args.tend,
          "pitch_m": pitch, "size": size, "density": rho, "settings_young_dt_poisson": SETTINGS}
results = {"rows": [dict(zip(header, r)) for r in rows]}
common.write_provenance(name + ".provenance.json", sys.argv[0], sys.argv[1:], params, results, wall)
