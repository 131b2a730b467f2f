"""Cube sliding on a fixed slab under gravity (BENCHMARKS.md section 4).

A cube of edge 0.05 m, density 2700 kg/m^3 (mass matters little: the Coulomb law makes the
deceleration mu g for any mass), starts at rest vertically at its static equilibrium overlap
with the slab (so no normal bouncing) with horizontal speed v0 along +x. Analytic:
stop time v0/(mu g), stop distance v0^2/(2 mu g).

Outputs <out>/sliding<tag>.csv (t, x, vx, z of the centre of mass) and
<out>/sliding<tag>.provenance.json (parameters, stop time / distance, analytic values).

Run: yade -n -x sliding.py --mu 0.5 --v0 3.0 --dt 1e-5 --young 1e8 --out results
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))
import common  # noqa: E402
import yade_setup as ys  # noqa: E402
from yade import O, PyRunner  # noqa: E402

p = ys.add_common_args(argparse.ArgumentParser(description=__doc__), dt=1e-5, young=1e8, mu=0.5)
p.add_argument("--v0", type=float, default=3.0, help="initial speed, m/s")
p.add_argument("--edge", type=float, default=0.05, help="cube edge, m")
p.add_argument("--density", type=float, default=2700.0)
p.add_argument("--tail", type=float, default=0.1, help="time simulated after the analytic stop, s")
p.add_argument("--max-rows", type=int, default=2000)
args = ys.parse(p, sys.argv)

a, g = args.edge, ys.G
t_stop_a = args.v0 / (args.mu * g)
d_stop_a = args.v0 ** 2 / (2 * args.mu * g)
mat = ys.material(args.young, args.poisson, args.mu, args.density)
kn = 0.5 * args.young                     # identical materials: series of the two youngs
mass = args.density * a ** 3
overlap = mass * g / (kn * a * a)         # static overlap depth: kn * (a^2 d) = m g

slab_len = d_stop_a + 4 * a
ys.add_slab(mat, -a, slab_len, -2 * a, 2 * a, top=0.0, thickness=a)
cube = ys.add_polyhedron(mat, common.cube_vertices(a, (-0.5 * a, -0.5 * a, -overlap)))
O.bodies[cube].state.vel = (args.v0, 0, 0)
x0 = O.bodies[cube].state.pos[0]

samples = []


def record():
    s = O.bodies[cube].state
    samples.append((O.time, s.pos[0] - x0, s.vel[0], s.pos[2]))


ys.setup_engines(args.dt, [PyRunner(command="record()", iterPeriod=10)])
record()
wall0 = time.time()
ys.run_steps((t_stop_a + args.tail) / args.dt)
wall = time.time() - wall0

# stop: first sample with vx <= 0 (interpolated); afterwards the cube rests on the
# tangential spring (no damping), so also report the mean position over the tail.
t_stop = x_stop = None
for i in range(1, len(samples)):
    if samples[i][2] <= 0.0 < samples[i - 1][2]:
        f = samples[i - 1][2] / (samples[i - 1][2] - samples[i][2])
        t_stop = samples[i - 1][0] + f * (samples[i][0] - samples[i - 1][0])
        x_stop = samples[i - 1][1] + f * (samples[i][1] - samples[i - 1][1])
        break
tail = [s for s in samples if t_stop is not None and s[0] > t_stop + 0.02]
x_rest = sum(s[1] for s in tail) / len(tail) if tail else None
results = {
    "stop_time_s": t_stop, "stop_distance_m": x_stop, "rest_distance_mean_m": x_rest,
    "analytic_stop_time_s": t_stop_a, "analytic_stop_distance_m": d_stop_a,
    "rel_err_stop_time": (t_stop - t_stop_a) / t_stop_a if t_stop else None,
    "rel_err_stop_distance": (x_stop - d_stop_a) / d_stop_a if x_stop else None,
    "steps": O.iter,
}
params = {"mu": args.mu, "v0": args.v0, "dt": args.dt, "young": args.young,
          "poisson": args.poisson, "kn_N_per_m3": kn, "ks_N_per_m": 0.5 * args.young * args.poisson,
          "edge_m": a, "density": args.density, "mass_kg": mass, "g": g,
          "initial_overlap_m": overlap, "floor": "fixed polyhedron slab, same material"}
os.makedirs(args.out, exist_ok=True)
name = os.path.join(args.out, "sliding" + args.tag)
common.write_csv(name + ".csv", ["t", "x", "vx", "z"], common.downsample(samples, args.max_rows))
common.write_provenance(name + ".provenance.json", sys.argv[0], sys.argv[1:], params, results, wall)
print("SLIDING", results, "wall %.1f s" % wall)
