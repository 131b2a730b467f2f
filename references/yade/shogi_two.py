"""Two shogi pieces standing in a row; the first, tilted past its balance angle, falls onto
the second (point-face dominated: the first piece's top corner meets the second's face).

Geometry: common.SHOGI_DEFAULT size (king, 32.0 x 28.7 x 9.7 mm, top thickness 60 %),
boxwood density 950 kg/m^3, pitch 0.8 x height along x, both pieces facing +x. Piece 0
starts at rest, standing on its front bottom edge, tilted by --tilt0 = 25 deg (the rigid
balance angle of the king piece is 20.4 deg); piece 1 starts upright, sunk to its static
overlap. Why these values (measured, see README): at pitch 0.6 piece 0 meets piece 1 after
~3 deg of fall and only leans on it; starting just past balance (21.5 deg) makes the fall
time hinge on how far the soft volumetric edge contact sinks (0.2-0.6 mm, estimated), i.e. on the
stiffness. One friction coefficient for
piece-piece and piece-floor contacts; fixed polyhedron slab floor.

Outputs <out>/shogi_two_mu<mu><tag>.csv: t, tilt_0, tilt_1 (deg from vertical, + toward +x),
x_0, z_0, x_1, z_1 (centre of mass, m); provenance JSON with the times at which piece 1
(the struck one) reaches 1 deg (it has been hit), 45 deg and 80 deg of tilt.

Run: yade -n -x shogi_two.py --mu 0.5 --dt 1e-5 --young 1e8 --out results
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))
import common  # noqa: E402
import shogi_scene as ss  # noqa: E402
import yade_setup as ys  # noqa: E402
from yade import O  # noqa: E402

p = ys.add_common_args(argparse.ArgumentParser(description=__doc__), dt=1e-5, young=1e8, mu=0.5)
ss.add_piece_args(p, pitch=0.8, pitch_help="spacing / piece height", tilt0=25.0, omega0=0.0,
                  tend=0.5, max_rows=2000)
args = ys.parse(p, sys.argv)

h, w, t = common.SHOGI_SIZES[args.size]
pitch = args.pitch * h
mat = ys.material(args.young, args.poisson, args.mu, args.density)
ss.add_floor(mat, -2 * h, pitch + 2 * h, -w, w)
sink = ss.standing_sink(args.size, args.density, args.young)
axes = [ss.add_piece(mat, 0.0, 0.0, args.tilt0, args.size, sink, args.omega0),
        ss.add_piece(mat, pitch, 0.0, 0.0, args.size, sink)]
rec = ss.Recorder(axes, period=max(1, int(round(2e-4 / args.dt))))
ys.setup_engines(args.dt, [rec.runner])
rec.sample()
wall0 = time.time()
ys.run_steps(args.tend / args.dt)
wall = time.time() - wall0

results = {"struck_" + k: v for k, v in ss.tilt_events(rec, 1).items()}
results.update({"falling_" + k: v for k, v in ss.tilt_events(rec, 0).items()})
results["final_tilt_deg"] = rec.final_tilts()
results["max_tilt_deg"] = rec.max_tilts()
results["steps"] = O.iter
params = {"mu": args.mu, "dt": args.dt, "young": args.young, "poisson": args.poisson,
          "kn_N_per_m3": 0.5 * args.young, "ks_N_per_m": 0.5 * args.young * args.poisson,
          "size": args.size, "h_w_t_m": [h, w, t], "top_ratio": common.TOP_RATIO,
          "density": args.density, "mass_kg": ss.piece_mass(args.size, args.density),
          "pitch_m": pitch, "tilt0_deg": args.tilt0, "omega0_rad_per_s": args.omega0,
          "balance_tilt_deg": common.shogi_critical_tilt_deg(args.size),
          "standing_sink_m": sink, "tend": args.tend, "record_period_s": rec.runner.iterPeriod * args.dt}
os.makedirs(args.out, exist_ok=True)
name = os.path.join(args.out, "shogi_two_mu%g%s" % (args.mu, args.tag))
common.write_csv(name + ".csv", rec.header(["0", "1"]), common.downsample(rec.rows, args.max_rows))
common.write_provenance(name + ".provenance.json", sys.argv[0], sys.argv[1:], params, results, wall)
print("SHOGI_TWO", results, "wall %.1f s" % wall)
