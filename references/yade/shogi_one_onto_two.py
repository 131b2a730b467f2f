"""One shogi piece falling onto two pieces standing side by side (edge-edge dominated).

Geometry: common.SHOGI_DEFAULT size (king, 32.0 x 28.7 x 9.7 mm, top thickness 60 %),
boxwood density 950 kg/m^3. Piece 0 (the striker) has its base centre at the origin and
starts at rest on its front bottom edge, tilted by --tilt0 = 25 deg toward +x (optionally
spinning at --omega0 rad/s about that edge); same start as shogi_two.py. Pieces 1 and 2
stand upright at x = 0.8 x height, side by side in y with a base gap of --gap x width
between them (centres at y = -/+ (width + gap)/2), so
the striker's roof edges meet the inner side edges of the pair: an eccentric, edge-edge
impact on each. One friction coefficient; fixed polyhedron slab floor.

Outputs <out>/shogi_one_onto_two_mu<mu><tag>.csv: t, tilt_0, tilt_1, tilt_2 (deg, + toward
+x), x_i, z_i (centre of mass, m); provenance JSON with the 1, 45 and 80 deg crossing times
of each struck piece, their maximum tilt and the left/right asymmetry of both (a check:
the scene is symmetric, so any asymmetry is numerical noise of the contact geometry).

Run: yade -n -x shogi_one_onto_two.py --mu 0.5 --out results
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
ss.add_piece_args(p, pitch=0.8, pitch_help="x spacing / piece height", tilt0=25.0, omega0=0.0,
                  tend=0.5, max_rows=2000, omega_help="initial spin of the striker (piece 0), rad/s")
p.add_argument("--gap", type=float, default=0.1, help="base gap between the pair / width")
args = ys.parse(p, sys.argv)

h, w, t = common.SHOGI_SIZES[args.size]
pitch, yc = args.pitch * h, 0.5 * (w + args.gap * w)
mat = ys.material(args.young, args.poisson, args.mu, args.density)
ss.add_floor(mat, -2 * h, pitch + 2 * h, -2 * w, 2 * w)
sink = ss.standing_sink(args.size, args.density, args.young)
axes = [ss.add_piece(mat, 0.0, 0.0, args.tilt0, args.size, omega0=args.omega0),
        ss.add_piece(mat, pitch, -yc, 0.0, args.size, sink),
        ss.add_piece(mat, pitch, yc, 0.0, args.size, sink)]
rec = ss.Recorder(axes, period=max(1, int(round(2e-4 / args.dt))))
ys.setup_engines(args.dt, [rec.runner])
rec.sample()
wall0 = time.time()
ys.run_steps(args.tend / args.dt)
wall = time.time() - wall0

results = {}
for k, name in ((0, "striker"), (1, "struck_left"), (2, "struck_right")):
    results.update({"%s_%s" % (name, key): v for key, v in ss.tilt_events(rec, k).items()})
results["final_tilt_deg"] = rec.final_tilts()
results["max_tilt_deg"] = rec.max_tilts()
for lv in ("1", "45"):   # left/right asymmetry of a symmetric scene: a numerical-noise check
    tl, tr = results["struck_left_t_tilt_%s_s" % lv], results["struck_right_t_tilt_%s_s" % lv]
    results["struck_t_tilt_%s_asymmetry_s" % lv] = abs(tl - tr) if tl and tr else None
results["struck_max_tilt_asymmetry_deg"] = abs(results["max_tilt_deg"][1] - results["max_tilt_deg"][2])
results["steps"] = O.iter
params = {"mu": args.mu, "dt": args.dt, "young": args.young, "poisson": args.poisson,
          "kn_N_per_m3": 0.5 * args.young, "ks_N_per_m": 0.5 * args.young * args.poisson,
          "size": args.size, "h_w_t_m": [h, w, t], "top_ratio": common.TOP_RATIO,
          "density": args.density, "mass_kg": ss.piece_mass(args.size, args.density),
          "pitch_m": pitch, "pair_centre_y_m": yc, "gap_m": args.gap * w,
          "tilt0_deg": args.tilt0, "omega0_rad_per_s": args.omega0,
          "standing_sink_m": sink, "tend": args.tend, "record_period_s": rec.runner.iterPeriod * args.dt}
os.makedirs(args.out, exist_ok=True)
name = os.path.join(args.out, "shogi_one_onto_two_mu%g%s" % (args.mu, args.tag))
common.write_csv(name + ".csv", rec.header(["0", "1", "2"]), common.downsample(rec.rows, args.max_rows))
common.write_provenance(name + ".provenance.json", sys.argv[0], sys.argv[1:], params, results, wall)
print("SHOGI_ONE_ONTO_TWO", results, "wall %.1f s" % wall)
