"""YADE-side helpers shared by the reference scripts (import only inside `yade -n -x`).

The engine list is the one in BENCHMARKS.md section 4, nothing added:
  ForceResetter, InsertionSortCollider([Bo1_Polyhedra_Aabb()]),
  InteractionLoop([Ig2_Polyhedra_Polyhedra_PolyhedraGeom()],
                  [Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                  [Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
  NewtonIntegrator(damping=0, gravity=(0, 0, -g)).

Contact law of YADE 2023.02a Polyhedra (read from its source, pkg/dem/Polyhedra_support.cpp):
  kn = Ea Eb / (Ea + Eb)                 [N/m^3]  (= young/2 for one material)
  ks = (Ea pa)(Eb pb) / (Ea pa + Eb pb)  [N/m]    (pa = PolyhedraMat.poisson: a stiffness ratio)
  Fn = kn * overlap_volume along the normal of the overlap polyhedron, no damping;
  Fs incremental elastic, |Fs| <= tan(min(phi_a, phi_b)) |Fn|.
So every collision is elastic apart from Coulomb slip; there is no normal dashpot.
"""
import math

from yade import O, polyhedra_utils
from yade.wrapper import (ForceResetter, InsertionSortCollider, Bo1_Polyhedra_Aabb,
                          InteractionLoop, Ig2_Polyhedra_Polyhedra_PolyhedraGeom,
                          Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys,
                          Law2_PolyhedraGeom_PolyhedraPhys_Volumetric, NewtonIntegrator,
                          PolyhedraMat)
from yade.minieigenHP import Vector3

G = 9.81


def add_common_args(p, dt, young, mu):
    """Arguments every script takes: time step, stiffness, friction, output folder."""
    p.add_argument("--mu", type=float, default=mu, help="friction coefficient (all contacts)")
    p.add_argument("--dt", type=float, default=dt, help="time step, s (set by hand)")
    p.add_argument("--young", type=float, default=young,
                   help="PolyhedraMat.young, volumetric stiffness N/m^3 (kn = young/2)")
    p.add_argument("--poisson", type=float, default=0.25,
                   help="PolyhedraMat.poisson = ks/kn-like ratio (ks = young*poisson/2, N/m)")
    p.add_argument("--out", default="results", help="output folder")
    p.add_argument("--tag", default="", help="suffix of the output names")
    return p


def parse(p, argv):
    """argparse on YADE's argv (argv[0] is the script)."""
    return p.parse_args(argv[1:])


def material(young, poisson, mu, density):
    return PolyhedraMat(young=young, poisson=poisson, frictionAngle=math.atan(mu),
                        density=density)


def setup_engines(dt, extra=()):
    """The section-4 engine list plus caller-supplied PyRunners; fixes O.dt."""
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Polyhedra_Aabb()]),
        InteractionLoop([Ig2_Polyhedra_Polyhedra_PolyhedraGeom()],
                        [Ip2_PolyhedraMat_PolyhedraMat_PolyhedraPhys()],
                        [Law2_PolyhedraGeom_PolyhedraPhys_Volumetric()]),
        NewtonIntegrator(damping=0.0, gravity=(0, 0, -G)),
    ] + list(extra)
    # PWaveTimeStep() returns 1.0 without spheres: the step is always set by hand.
    O.dt = dt


def add_polyhedron(mat, verts, fixed=False):
    """Body from world-frame vertices (YADE re-centres them; pos = centroid)."""
    b = polyhedra_utils.polyhedra(mat, v=[Vector3(*v) for v in verts], fixed=fixed)
    return O.bodies.append(b)


def add_slab(mat, x0, x1, y0, y1, top=0.0, thickness=0.05):
    """Fixed floor: a box polyhedron whose top face is z = top."""
    verts = [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (top - thickness, top)]
    return add_polyhedron(mat, verts, fixed=True)


class BodyAxis:
    """Tracks a body-fixed direction given in world coordinates at creation."""

    def __init__(self, body_id, world_dir):
        b = O.bodies[body_id]
        self.id = body_id
        self.local = b.state.ori.conjugate() * Vector3(*world_dir)

    def world(self):
        return O.bodies[self.id].state.ori * self.local

    def com_xz(self):
        p = O.bodies[self.id].state.pos
        return (p[0], p[2])

    def tilt_deg(self):
        """Signed angle of the axis from vertical, positive toward +x."""
        a = self.world()
        return math.degrees(math.atan2(a[0], a[2]))


def run_steps(n):
    O.run(int(n), True)
