"""Rigid-body reference for a king piece leaning against a vertical wall (the ladder problem):
the piece (exact polyhedron of references/yade/common.py, 950 kg/m^3) stands on its front
bottom edge (the foot) on the floor and touches the wall with the front end of its apex ridge.
Both are point contacts of ideal rigid bodies with Coulomb friction mu (kinetic = static).

Planar motion in the x-z plane (the scene is symmetric in the width). Phase 1: both contacts
slide (foot away from the wall, apex down it); the configuration is fixed by the tilt, and
each step solves Newton-Euler with the two contact constraints for the angular acceleration
and the normal forces. Phase 2 (after the wall's normal force reaches zero): the foot alone,
sliding. Ends when the apex reaches the floor (the piece lies on its front face).

  static_limit(mu_floor, mu_wall)  tilt (deg) above which the leaning piece cannot stand
  slide(mu, tilt0)                 times at which the tilt rises through given levels
  effective_mu(t, tilt0, level)    the mu for which the rigid piece reaches `level` at time t

Run: /usr/bin/python3 rigid_ladder.py (prints the references used by the test).
"""
import math
import sys
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "references" / "yade"))
import common  # noqa: E402

G = 9.81
RHO = common.BOXWOOD_DENSITY


def mass_properties(size=common.SHOGI_DEFAULT):
    """Mass, centre height above the base and moment of inertia about the width axis through
    the centre (exact polyhedron, tets from the centre to each boundary triangle)."""
    v = np.array(common.shogi_vertices(size))
    faces = common.shogi_faces()
    vol, c = common.polyhedron_volume_centroid([tuple(p) for p in v], faces)
    c = np.array(c)
    second = np.zeros((3, 3))
    for tri in faces:
        p = np.vstack([np.zeros(3), v[list(tri)] - c])
        tet_vol = np.linalg.det(p[1:] - p[0]) / 6.0
        s = p.sum(0)
        second += tet_vol / 20.0 * (sum(np.outer(q, q) for q in p) + np.outer(s, s))
    return RHO * vol, c[2], RHO * (second[0, 0] + second[2, 2])


H, W, T = common.SHOGI_SIZES[common.SHOGI_DEFAULT]
M, ZC, I = mass_properties()
FOOT = np.array([0.5 * T, -ZC])                       # front bottom edge, relative to the centre
APEX = np.array([0.5 * common.TOP_RATIO * T, H - ZC])  # front end of the apex ridge


def rot(th, r):
    """(x, z) of body vector r after a tilt th (rad) toward +x."""
    c, s = math.cos(th), math.sin(th)
    return np.array([c * r[0] + s * r[1], -s * r[0] + c * r[1]])


def drot(th, r):
    """d rot(th, r) / d th."""
    p = rot(th, r)
    return np.array([p[1], -p[0]])


def static_limit(mu_floor, mu_wall):
    """Largest tilt (deg) at which friction at its limit on both contacts still holds the piece."""
    def tips(th):
        f, a = rot(th, FOOT), rot(th, APEX)
        n1 = M * G / (1.0 + mu_floor * mu_wall)
        n2 = mu_floor * n1
        # moment about the centre (+: tilts further) of floor (mu n1, n1) at f, wall (-n2, mu n2) at a
        return (f[1] * mu_floor * n1 - f[0] * n1) + (a[1] * -n2 - a[0] * mu_wall * n2) > 0.0

    lo, hi = math.radians(common.shogi_critical_tilt_deg()), math.radians(89.0)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if tips(mid) else (mid, hi)
    return math.degrees(lo)


def _both(th, om, mu):
    """Phase 1: angular acceleration and normal forces (floor n1, wall n2); both contacts slide
    (foot toward -x, apex down)."""
    f, a, df, da = rot(th, FOOT), rot(th, APEX), drot(th, FOOT), drot(th, APEX)
    # unknowns: centre acceleration ax, az, angular acceleration, n1, n2
    A = np.array([[M, 0.0, 0.0, -mu, 1.0],                      # m ax = mu n1 - n2
                  [0.0, M, 0.0, -1.0, -mu],                     # m az = n1 + mu n2 - m g
                  [0.0, 0.0, I, -(mu * df[0] + df[1]), -(-da[0] + mu * da[1])],
                  [0.0, 1.0, df[1], 0.0, 0.0],                  # foot stays on the floor
                  [1.0, 0.0, da[0], 0.0, 0.0]])                 # apex stays on the wall
    b = np.array([0.0, -M * G, 0.0, om * om * f[1], om * om * a[0]])
    return np.linalg.solve(A, b)


def _foot(th, om, vx, mu):
    """Phase 2: the foot alone, sliding: centre x acceleration and angular acceleration."""
    f, df = rot(th, FOOT), drot(th, FOOT)
    sgn = -1.0 if vx + om * df[0] < 0.0 else 1.0  # friction opposes the foot's slip
    k = -sgn * mu
    A = np.array([[M, 0.0, 0.0, -k], [0.0, M, 0.0, -1.0],
                  [0.0, 0.0, I, -(k * df[0] + df[1])], [0.0, 1.0, df[1], 0.0]])
    b = np.array([0.0, -M * G, 0.0, om * om * f[1]])
    return np.linalg.solve(A, b)


def slide(mu, tilt0, levels=(80.0, 85.0)):
    """Released at rest at tilt0 (deg): {level: (first time the tilt reaches it, energy lost
    to friction by then)} (None if it never does: friction holds the piece), the time and tilt
    at which the apex leaves the wall (None if it never does), and the tilt history (times, deg)
    up to the landing."""
    z0 = -rot(math.radians(tilt0), FOOT)[1]

    def lost(th, om, vx):
        """Potential energy released minus kinetic energy (the foot is on the floor)."""
        vz = -om * drot(th, FOOT)[1]
        return M * G * (z0 + rot(th, FOOT)[1]) - 0.5 * (M * (vx * vx + vz * vz) + I * om * om)
    def rhs1(t, y):
        return [y[1], _both(y[0], y[1], mu)[2]]

    def leaves(t, y):
        return _both(y[0], y[1], mu)[4]
    leaves.terminal, leaves.direction = True, -1

    def lands(t, y):
        return rot(y[0], APEX)[1] - rot(y[0], FOOT)[1]  # apex height above the foot
    lands.terminal = True

    def at(level):
        ev = lambda t, y: y[0] - math.radians(level)  # noqa: E731
        return ev
    marks = [at(lv) for lv in levels]
    kw = dict(rtol=1e-10, atol=1e-12, max_step=1e-4)
    if _both(math.radians(tilt0), 0.0, mu)[2] <= 0.0:  # friction holds it: nothing slides
        return {lv: None for lv in levels}, None, (np.zeros(1), np.full(1, tilt0))
    s1 = solve_ivp(rhs1, [0.0, 1.0], [math.radians(tilt0), 0.0], events=marks + [leaves, lands], **kw)
    times = {lv: None for lv in levels}
    for k, lv in enumerate(levels):
        if s1.t_events[k].size:
            th, om = s1.y_events[k][0]
            times[lv] = (float(s1.t_events[k][0]), lost(th, om, -om * drot(th, APEX)[0]))
    sep, t_hist, a_hist = None, list(s1.t), list(np.degrees(s1.y[0]))
    if s1.t_events[len(levels)].size:
        t0, (th, om) = s1.t_events[len(levels)][0], s1.y_events[len(levels)][0]
        sep = (float(t0), math.degrees(th))
        vx = -om * drot(th, APEX)[0]  # the centre's x velocity while the apex was held at the wall

        def rhs2(t, y):
            acc = _foot(y[1], y[3], y[2], mu)
            return [y[2], y[3], acc[0], acc[2]]

        def lands2(t, y):
            return lands(t, y[1:2])
        lands2.terminal = True
        marks2 = [(lambda lv: (lambda t, y: y[1] - math.radians(lv)))(lv) for lv in levels]
        s2 = solve_ivp(rhs2, [t0, 1.0], [0.0, th, vx, om], events=marks2 + [lands2], **kw)
        for k, lv in enumerate(levels):
            if times[lv] is None and s2.t_events[k].size:
                _, th, vx, om = s2.y_events[k][0]
                times[lv] = (float(s2.t_events[k][0]), lost(th, om, vx))
        t_hist += list(s2.t)
        a_hist += list(np.degrees(s2.y[1]))
    return times, sep, (np.array(t_hist), np.array(a_hist))


def effective_mu(t, tilt0, level=85.0):
    """Friction coefficient (both contacts) with which the rigid piece released at tilt0 reaches
    `level` at time t; None outside [0, 0.55] (t is then below the frictionless time or the
    piece would be held). The time grows with mu; it is insensitive to mu below ~0.2."""
    from scipy.optimize import brentq

    def late(mu):
        hit = slide(mu, tilt0, (level,))[0][level]
        return (hit[0] if hit else math.inf) - t
    if late(0.0) > 0.0 or late(0.55) < 0.0:
        return None
    return brentq(late, 0.0, 0.55, xtol=5e-4)


if __name__ == "__main__":
    print(f"mass {M * 1e3:.4f} g, centre {ZC * 1e3:.3f} mm, I_yy {I:.4e} kg m^2")
    for mu in (0.1, 0.3, 0.5):
        times, sep, _ = slide(mu, 76.0)
        print(f"mu {mu}: static limit {static_limit(mu, mu):.2f} deg; from 76 deg: "
              + ", ".join(f"{lv:g} deg at {t:.5f} s (friction work {w:.4e} J)" for lv, (t, w) in times.items())
              + (f"; apex leaves the wall at {sep[0]:.5f} s, {sep[1]:.2f} deg" if sep else ""))
