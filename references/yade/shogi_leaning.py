"""A shogi piece leaning against a fixed block slides down it (the ladder problem): the
canonical case of the chain's sliding contacts between leaning pieces (issue 5).

Geometry: common.SHOGI_DEFAULT size (king), boxwood 950 kg/m^3. The piece stands on its
front bottom edge (x = T/2, z = 0), tilted by --tilt0 toward +x; a fixed box block (the
"wall", 20 mm thick, 2 w wide, 50 mm high) has its face x = x_w at the piece's
farthest point, the front end of its apex ridge, which therefore touches the face (a vertex
sliding on a face: the leaning piece's apex on the next piece's back face in the chain). The
floor is the usual fixed slab. Released at rest, the piece slides down: its foot slides on
the floor away from the block, its apex down the block's face, until it lies on its front
face (tilt 93.5 deg). One friction coefficient for the floor and the block.

Rigid statics (both contacts at the Coulomb limit): the piece holds below 32.6 deg (mu 0.1),
53.8 deg (0.3), 71.2 deg (0.5); --tilt0 = 76 deg is above all three, so the slide starts at
release for each mu.

Outputs <out>/shogi_leaning_mu<mu><tag>.csv: t, tilt_0 (deg from vertical, + toward +x),
x_0, z_0 (centre of mass, m); provenance JSON with the times at which the tilt rises through
80 and 85 deg (the piece lands on its front face at 93.5 deg, then bounces on YADE's undamped
contacts: only the first slide is a reference).

Run: yade -n -x shogi_leaning.py --mu 0.5 --dt 1e-5 --young 1e8 --out results
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
ss.add_piece_args(p, pitch=0.0, pitch_help="unused (one piece)", tilt0=76.0, omega0=0.0,
                  tend=0.12, max_rows=2000)
args = ys.parse(p, sys.argv)

h, w, t = common.SHOGI_SIZES[args.size]
mat = ys.material(args.young, args.poisson, args.mu, args.density)
verts = common.shogi_tilt_frame(args.tilt0, (0.0, 0.0, 0.0), args.size)
apex = max(verts, key=lambda v: v[0])
x_w = apex[0]
ss.add_floor(mat, -2 * h, x_w + 2 * h, -w, w)
BLOCK_TOP = 0.05  # m, well above the apex
ys.add_polyhedron(mat, [(x, y, z) for x in (x_w, x_w + 0.02) for y in (-w, w) for z in (0.0, BLOCK_TOP)],
                  fixed=True)
axis = ss.add_piece(mat, 0.0, 0.0, args.tilt0, args.size)
rec = ss.Recorder([axis], period=max(1, int(round(1e-4 / args.dt))))
ys.setup_engines(args.dt, [rec.runner])
rec.sample()
wall0 = time.time()
ys.run_steps(args.tend / args.dt)
wall_s = time.time() - wall0

results = ss.tilt_events(rec, 0, levels=(80.0, 85.0))
results["final_tilt_deg"] = rec.final_tilts()[0]
results["steps"] = O.iter
params = {"mu": args.mu, "dt": args.dt, "young": args.young, "poisson": args.poisson,
          "kn_N_per_m3": 0.5 * args.young, "ks_N_per_m": 0.5 * args.young * args.poisson,
          "size": args.size, "h_w_t_m": [h, w, t], "top_ratio": common.TOP_RATIO,
          "density": args.density, "mass_kg": ss.piece_mass(args.size, args.density),
          "tilt0_deg": args.tilt0, "block_face_x_m": x_w, "apex_m": list(apex),
          "block_top_m": BLOCK_TOP, "tend": args.tend,
          "record_period_s": rec.runner.iterPeriod * args.dt}
os.makedirs(args.out, exist_ok=True)
name = os.path.join(args.out, "shogi_leaning_mu%g%s" % (args.mu, args.tag))
common.write_csv(name + ".csv", rec.header(["0"]), common.downsample(rec.rows, args.max_rows))
common.write_provenance(name + ".provenance.json", sys.argv[0], sys.argv[1:], params, results, wall_s)
print("SHOGI_LEANING", results, "wall %.1f s" % wall_s)
