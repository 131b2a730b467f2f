"""A row of n shogi pieces toppling like dominoes (BENCHMARKS.md section 5, van Leeuwen 2010).

Geometry: common.SHOGI_DEFAULT size (king, 32.0 x 28.7 x 9.7 mm, top thickness 60 %),
boxwood density 950 kg/m^3, pieces upright along x at pitch --pitch x height (base centres
x_i = i * pitch), sunk to their static overlap. Piece 0 starts tilted by --tilt0 about its
front bottom edge and spinning about that edge at --omega0 rad/s (the push). One friction
coefficient for every contact; fixed polyhedron slab floor.

Front: piece i has fallen when its tilt first reaches --front-tilt (45 deg); the front at
time t is the farthest fallen piece (index, x_i). Front speed = least-squares slope of x_i
against those times over the steady part (pieces n/4 .. n-2).

--lazy (default): piece i+1 is inserted, upright at rest in its static equilibrium, when
piece i first tilts past --insert-tilt (5 deg). Piece i cannot touch i+1 before ~25 deg,
so the dynamics are those of the full row, while the untouched pieces' floor contacts (the
bulk of the CGAL cost) are skipped. --no-lazy places every piece from the start.

Outputs <out>/shogi_chain_n<n><tag>.csv: t, front_index, front_x, tilt_0 .. tilt_{n-1} (deg);
provenance JSON with the per-piece fall times and the front speed.

Run: yade -n -x shogi_chain.py --n 40 --out results
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

p = ys.add_common_args(argparse.ArgumentParser(description=__doc__), dt=2e-5, young=1e7, mu=0.5)
ss.add_piece_args(p, pitch=0.6, pitch_help="spacing / piece height", tilt0=21.5, omega0=5.0,
                  tend=3.0, max_rows=1000, omega_help="initial spin of piece 0, rad/s",
                  tend_help="upper bound of simulated time, s")
p.add_argument("--n", type=int, default=40)
p.add_argument("--front-tilt", type=float, default=45.0)
p.add_argument("--insert-tilt", type=float, default=5.0)
p.add_argument("--lazy", action=argparse.BooleanOptionalAction, default=True)
p.add_argument("--tail", type=float, default=0.05, help="time kept after the last piece falls")
args = ys.parse(p, sys.argv)

h, w, t = common.SHOGI_SIZES[args.size]
pitch = args.pitch * h
mat = ys.material(args.young, args.poisson, args.mu, args.density)
ss.add_floor(mat, -2 * h, (args.n - 1) * pitch + 2 * h, -w, w)
sink = ss.standing_sink(args.size, args.density, args.young)
z_com = common.polyhedron_volume_centroid(common.shogi_vertices(args.size),
                                          common.shogi_faces())[1][2] - sink


def insert(i):
    axes[i] = ss.add_piece(mat, i * pitch, 0.0, 0.0, args.size, sink)


axes = [ss.Standing(i * pitch, z_com) for i in range(args.n)]
axes[0] = ss.add_piece(mat, 0.0, 0.0, args.tilt0, args.size, omega0=args.omega0)
n_inserted = 1
if not args.lazy:
    for i in range(1, args.n):
        insert(i)
    n_inserted = args.n


def grow():
    global n_inserted
    while n_inserted < args.n and axes[n_inserted - 1].tilt_deg() > args.insert_tilt:
        insert(n_inserted)
        n_inserted += 1


if args.lazy:
    insert(1)
    n_inserted = 2
import builtins  # noqa: E402
builtins.grow = grow
period = max(1, int(round(2e-4 / args.dt)))
rec = ss.Recorder(axes, period=period)
ys.setup_engines(args.dt, [PyRunner(command="grow()", iterPeriod=period), rec.runner])
rec.sample()
wall0 = time.time()
t_last = None
while O.time < args.tend:
    ys.run_steps(0.01 / args.dt)
    if t_last is None and axes[-1].tilt_deg() >= args.front_tilt:
        t_last = O.time
    if t_last is not None and O.time >= t_last + args.tail:
        break
wall = time.time() - wall0

times = [r[0] for r in rec.rows]
fall = [common.crossing_time(*rec.series(i), args.front_tilt) for i in range(args.n)]
rows = []
for r in rec.rows:
    k = max([i for i in range(args.n) if fall[i] is not None and fall[i] <= r[0]], default=-1)
    rows.append([r[0], k, k * pitch if k >= 0 else float("nan")] + r[1:1 + args.n])
fallen = [i for i in range(args.n) if fall[i] is not None]
results = {"fall_time_s": fall, "n_fallen": len(fallen), "steps": O.iter, "t_end_s": O.time}
i0, i1 = max(3, args.n // 4), args.n - 1           # steady part: pieces i0 .. n-2
win = [i for i in range(i0, i1) if fall[i] is not None]
if len(win) >= 4:
    speed, _ = common.linear_fit([fall[i] for i in win], [i * pitch for i in win])
    half = len(win) // 2
    s1, _ = common.linear_fit([fall[i] for i in win[:half]], [i * pitch for i in win[:half]])
    s2, _ = common.linear_fit([fall[i] for i in win[half:]], [i * pitch for i in win[half:]])
    results.update({"front_speed_m_per_s": speed, "front_speed_first_half": s1,
                    "front_speed_second_half": s2, "fit_pieces": [win[0], win[-1]],
                    "front_speed_over_sqrt_gh": speed / (ys.G * h) ** 0.5})
params = {"n": args.n, "mu": args.mu, "dt": args.dt, "young": args.young, "poisson": args.poisson,
          "kn_N_per_m3": 0.5 * args.young, "ks_N_per_m": 0.5 * args.young * args.poisson,
          "size": args.size, "h_w_t_m": [h, w, t], "top_ratio": common.TOP_RATIO,
          "density": args.density, "mass_kg": ss.piece_mass(args.size, args.density),
          "pitch_m": pitch, "tilt0_deg": args.tilt0, "omega0_rad_per_s": args.omega0,
          "front_tilt_deg": args.front_tilt, "lazy": args.lazy, "insert_tilt_deg": args.insert_tilt,
          "standing_sink_m": sink, "record_period_s": period * args.dt}
os.makedirs(args.out, exist_ok=True)
name = os.path.join(args.out, "shogi_chain_n%d%s" % (args.n, args.tag))
header = ["t", "front_index", "front_x"] + ["tilt_%d" % i for i in range(args.n)]
common.write_csv(name + ".csv", header, common.downsample(rows, args.max_rows), fmt="%.5g")
common.write_provenance(name + ".provenance.json", sys.argv[0], sys.argv[1:], params, results, wall)
print("SHOGI_CHAIN", {k: v for k, v in results.items() if k != "fall_time_s"}, "wall %.1f s" % wall)
print("FALL_TIMES", ["%.4f" % x if x is not None else None for x in fall])
