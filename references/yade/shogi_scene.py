"""Shogi-piece scenes for YADE: placing pieces, recording tilt / centre of mass, events.

Shared by shogi_two.py, shogi_one_onto_two.py and shogi_chain.py (import inside YADE only).
Piece frame and geometry: common.shogi_vertices (thickness along x, width along y, height z);
pieces fall toward +x about their front bottom edge.
"""
import math

import common
import yade_setup as ys
from yade import O, PyRunner
from yade.minieigenHP import Vector3


def add_piece_args(p, pitch, pitch_help, tilt0, omega0, tend, max_rows,
                   omega_help="initial spin of piece 0 about its front bottom edge, rad/s",
                   tend_help="simulated time, s"):
    """Arguments every shogi script takes: spacing, the first piece's start, run length,
    material density, piece size, CSV row cap."""
    p.add_argument("--pitch", type=float, default=pitch, help=pitch_help)
    p.add_argument("--tilt0", type=float, default=tilt0, help="initial tilt of piece 0, deg")
    p.add_argument("--omega0", type=float, default=omega0, help=omega_help)
    p.add_argument("--tend", type=float, default=tend, help=tend_help)
    p.add_argument("--density", type=float, default=common.BOXWOOD_DENSITY)
    p.add_argument("--size", default=common.SHOGI_DEFAULT, choices=sorted(common.SHOGI_SIZES))
    p.add_argument("--max-rows", type=int, default=max_rows)
    return p


def piece_mass(size, density):
    vol, _ = common.polyhedron_volume_centroid(common.shogi_vertices(size), common.shogi_faces())
    return vol * density


def standing_sink(size, density, young):
    """Depth at which an upright piece's base overlap carries its weight: (young/2) * A d = m g."""
    h, w, t = common.SHOGI_SIZES[size] if isinstance(size, str) else size
    base_area = w * t
    return piece_mass(size, density) * ys.G / (0.5 * young * base_area)


def add_piece(mat, x, y, tilt_deg, size, sink=0.0, omega0=0.0):
    """Piece with base centre at (x, y, -sink), tilted toward +x about its front bottom edge
    (a tilted piece stands on that edge at z = 0), optionally spinning about that edge at
    omega0 rad/s (> 0 tips it toward +x). Returns a BodyAxis tracking its height axis."""
    verts = common.shogi_tilt_frame(tilt_deg, (x, y, -sink if tilt_deg == 0 else 0.0), size)
    bid = ys.add_polyhedron(mat, verts)
    if omega0:
        # NB (2026-11-25): YADE 2023.02a's NewtonIntegrator integrates an aspherical body's
        # rotation from state.angMom (zero here) and overwrites angVel at the first step, so the
        # spin set below is lost: the piece starts with only its centre's velocity (README.md,
        # "Frictionless chain"). Kept as it is so that the stored chain runs stay reproducible.
        h, w, t = common.SHOGI_SIZES[size] if isinstance(size, str) else size
        st = O.bodies[bid].state
        st.angVel = Vector3(0.0, omega0, 0.0)
        st.vel = st.angVel.cross(st.pos - Vector3(x + 0.5 * t, y, 0.0))
    a = math.radians(tilt_deg)
    return ys.BodyAxis(bid, (math.sin(a), 0.0, math.cos(a)))


class Standing:
    """Stand-in for a piece not yet inserted (shogi_chain --lazy): upright, at rest."""

    def __init__(self, x, z):
        self.id, self._com = None, (x, z)

    def tilt_deg(self):
        return 0.0

    def com_xz(self):
        return self._com


def add_floor(mat, xmin, xmax, ymin, ymax):
    return ys.add_slab(mat, xmin, xmax, ymin, ymax, top=0.0, thickness=0.02)


class Recorder:
    """Samples t, tilt (deg, signed toward +x) and centre-of-mass x, z of each piece."""

    def __init__(self, axes, period):
        self.axes = axes
        self.rows = []
        self.runner = PyRunner(command="_shogi_recorder.sample()", iterPeriod=period)
        import builtins
        builtins._shogi_recorder = self   # PyRunner commands run in YADE's __main__/builtins

    def sample(self):
        row = [O.time]
        for ax in self.axes:
            row.append(ax.tilt_deg())
        for ax in self.axes:
            row.extend(ax.com_xz())
        self.rows.append(row)

    def header(self, names):
        return (["t"] + ["tilt_%s" % n for n in names]
                + [c for n in names for c in ("x_%s" % n, "z_%s" % n)])

    def series(self, k):
        """(times, tilt of piece k)."""
        return [r[0] for r in self.rows], [r[1 + k] for r in self.rows]

    def max_tilts(self):
        return [max(r[1 + k] for r in self.rows) for k in range(len(self.axes))]

    def final_tilts(self):
        return [self.rows[-1][1 + k] for k in range(len(self.axes))]


def tilt_events(rec, k, levels=(1.0, 45.0, 80.0)):
    """First times piece k's tilt rises through each level (None if never)."""
    t, a = rec.series(k)
    return {"t_tilt_%g_s" % lv: common.crossing_time(t, a, lv) for lv in levels}
