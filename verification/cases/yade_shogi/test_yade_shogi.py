"""qdemsph against YADE (Polyhedra, Debian yade 2023.02a) for two king pieces 30 mm apart:
the first, tilted 25 deg, falls onto the second (contact_shogi's scene_pair.yaml, put on
YADE's geometry by --set overrides). Tilt histories of both pieces on one axis, the struck
piece's 45 deg time, the outcome, and the effect of friction (mu 0.1 -> 0.5) in both codes.
Stored YADE runs: references/yade/results/shogi_two_mu*_pitch30mm*.csv. See README.md."""
import csv
import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from harness import must
from harness.paths import REPO
from harness.shogi import crossing, tilt_history

SCENE = REPO / "verification" / "cases" / "contact_shogi" / "scene_pair.yaml"
YADE = REPO / "references" / "yade" / "results"
TILT0 = 25.0
H, W, T = 0.032, 0.0287, 0.0097
PITCH = 0.030
# scene_pair.yaml turns the tilted piece about its base-centre line (x axis), so its leading
# bottom edge (the pivot) lands at y = -T/2 cos 25 and its base-centre-to-pivot distance is
# 0.45 mm shorter than YADE's, where the piece turns about that edge (pivot at T/2 from the
# base centre, struck piece's base centre 30 mm from the tilted one's). Shift the tilted
# piece by -T/2 (1 - cos 25) in y so the pivot sits at y = -T/2 and the pivot-to-struck-face
# gap is YADE's 30 - 9.7 = 20.3 mm; z keeps the scene's 0.2 mm (= D_DEM) edge clearance.
SHIFT_Y = -0.5 * T * (1.0 - math.cos(math.radians(TILT0)))
MATCH = [f"bodies.0.mesh.translate=[0, {SHIFT_Y:.7f}, 0.00225]",
         "output.fields_every=0.002", "run.end_time=0.32"]
# Tolerances (README.md): YADE's stiffness spread at 30 mm is 1.6 % (struck 45 deg), 1.8 %
# (struck 80 deg), 2.0 % (falling 45 deg), 0.7-0.8 % (hit); plus the contact-law difference
# (volumetric undamped vs spring-dashpot with restitution 0.3 on elastic tets), as in
# references/yade/README.md: times to +-5 %, the hit to +-2 %. They are applied to YADE's
# times extrapolated to rigid contact (yade_events), which moves each reference by its
# spread; the deviations from the stored young = 1e8 run are recorded as info.
TOL_T = 0.05
TOL_HIT = 0.02
# Friction effect on the falling piece's 45 deg time, (t(0.5) - t(0.1)) / t(0.1): YADE
# +7.09 % (base) and +7.14 % (4 x young). Common-mode model differences cancel in the
# ratio; we require the sign and the size to within half the YADE effect (+-3.5 points).
TOL_FRICTION = 0.035
TOPPLED = 45.0  # deg: a piece past 45 deg has fallen

VARIANTS = {
    # quick tier: contact_shogi's coarse pieces (220 tets) and material (E = 5e6 Pa)
    "coarse_E5e6": [],
    # rigid limit: same coarse pieces, stiff bodies
    "coarse_E1e9": ["materials.boxwood.E=1.0e9"],
    # contact_shogi's long-tier pieces (~2,600 tets), E = 5e6 Pa
    "fine_E5e6": ["bodies.0.mesh.mesh_size=null", "bodies.1.mesh.mesh_size=null"],
    # boxwood stiffness (E ~ 1e10 Pa along the grain), coarse pieces
    "coarse_E1e10": ["materials.boxwood.E=1.0e10"],
}


def geometry(p0, body, tets):
    """Pivot y, struck piece's back-face y at the base, masses (from the tet mesh), initial tilt."""
    vol = np.zeros(2)
    a, b, c, d = (p0[tets[:, i]] for i in range(4))
    v = np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6.0
    for k in range(2):
        vol[k] = v[body[tets[:, 0]] == k].sum()
    tilted, struck = p0[body == 0], p0[body == 1]
    edge = tilted[tilted[:, 2] < tilted[:, 2].min() + 1e-6]  # the leading bottom edge
    return {"pivot_y": float(edge[:, 1].mean()), "struck_back_y": float(struck[:, 1].max()),
            "mass_tilted": float(vol[0] * 950.0), "mass_struck": float(vol[1] * 950.0),
            "pivot_z": float(tilted[:, 2].min())}


def yade(mu, tag=""):
    name = YADE / f"shogi_two_mu{mu}_pitch30mm{tag}"
    with open(f"{name}.csv") as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    prov = json.loads(Path(f"{name}.provenance.json").read_text())
    return data[:, 0], data[:, 1], data[:, 2], prov


KEYS = {"hit": "struck_t_tilt_1_s", "struck45": "struck_t_tilt_45_s",
        "struck80": "struck_t_tilt_80_s", "falling45": "falling_t_tilt_45_s"}


def yade_events(mu):
    """YADE's event times at young = 1e8 (base) and 4e8 (stiff4) and their extrapolation to
    rigid contact, 2 t(4e8) - t(1e8): the error is set by how far the edge / corner sinks,
    which halves when young is quadrupled (edge overlap volume ~ depth^2). For the falling
    piece at mu 0.5 this gives 0.1056 s against 0.1058 s for a rigid piece turning about a
    fixed edge (rigid_t45); the base run is 4 % early. Max tilt: base run."""
    base = yade(mu)[3]["results"]
    stiff = yade(mu, "_stiff4")[3]["results"]
    ev = {"struck_max": base["max_tilt_deg"][1]}
    for k, key in KEYS.items():
        b, s4 = base[key], stiff[key]
        ev[k] = None if b is None or s4 is None else 2.0 * s4 - b
        ev[k + "_base"], ev[k + "_stiff4"] = b, s4
    return ev


def rigid_t45(p0, body, tets):
    """Time for a rigid king piece released at 25 deg on its leading bottom edge (a fixed,
    no-slip pivot) to reach 45 deg; exact mass, centre and inertia of the tet mesh's polyhedron
    (mesh-independent: the piece is a polyhedron)."""
    from scipy.integrate import solve_ivp

    sel = body[tets[:, 0]] == 0
    x = [p0[tets[sel, i]] for i in range(4)]
    vol = np.abs(np.einsum("ij,ij->i", x[1] - x[0], np.cross(x[2] - x[0], x[3] - x[0]))) / 6.0
    pts = p0[body == 0]
    piv = np.array([0.0, pts[pts[:, 2] < pts[:, 2].min() + 1e-6, 1].mean(), pts[:, 2].min()])
    com = (vol[:, None] * sum(x) / 4).sum(0) / vol.sum() - piv

    def r2(q):
        d = q - piv
        return d[..., 1] ** 2 + d[..., 2] ** 2

    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    inertia = (vol * (-sum(r2(q) for q in x) / 20 + sum(r2((x[i] + x[j]) / 2) for i, j in pairs) / 5)).sum()
    d = math.hypot(com[1], com[2])
    phi0 = math.atan2(-com[1], com[2])  # centre past the pivot, rad
    k = vol.sum() * 9.81 * d / inertia  # density cancels
    hit = lambda t, y: y[0] - phi0 - math.radians(20.0)  # noqa: E731
    hit.terminal = True
    sol = solve_ivp(lambda t, y: [y[1], k * math.sin(y[0])], [0, 1], [phi0, 0.0], events=hit,
                    rtol=1e-10, atol=1e-12)
    return float(sol.t_events[0][0])


def run_variant(variant, qdemsph, checks, case_out):
    res = {}
    for mu in (0.1, 0.5):
        run = must(qdemsph.run, SCENE, case_out / f"mu{mu}",
                   sets=MATCH + VARIANTS[variant] + [f"contact.mu={mu}", f"walls.0.mu={mu}"])
        m = f"{variant}.mu{mu}."
        checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min",
                     tolerance=1.0, unit="bool")
        t, (a0, a1), p0, body = tilt_history(run.out / "fields.h5", [TILT0, 0.0])
        wall = run.solver_wall_s
        ev = {"hit": crossing(t, a1, 1.0), "struck45": crossing(t, a1, 45.0),
              "struck80": crossing(t, a1, 80.0), "falling45": crossing(t, a0, 45.0),
              "struck_max": float(a1.max())}
        ty, y0, y1, _ = yade(mu)
        yev = yade_events(mu)
        res[mu] = (ev, yev)
        for k in ("hit", "struck45", "falling45"):
            if ev[k] is not None and yev[k + "_base"] is not None:
                checks.info(m + k + "_vs_yade_base", ev[k] / yev[k + "_base"] - 1.0, unit="-",
                            reference=yev[k + "_base"],
                            note="relative to the stored YADE young = 1e8 run (not stiffness-converged)")
        if mu == 0.5:
            # No slip at mu 0.5 before the hit: a rigid piece turning about its edge. Lumped
            # vertex masses raise the coarse pieces' inertia by 4.2 % (2.1 % in time).
            with h5py.File(run.out / "fields.h5", "r") as f:
                tets = np.asarray(f["mesh/tets"], dtype=np.int64)
            checks.check(m + "falling_t45_vs_rigid", ev["falling45"], kind="rel",
                         reference=rigid_t45(p0, body, tets), tolerance=0.03, unit="s", wall_s=wall,
                         note="rigid piece about a fixed edge, exact polyhedron inertia")
        checks.info(m + "wall", wall, unit="s", wall_s=wall)
        if mu == 0.1:
            # The outcome, YADE's robust result: the struck piece rocks (max 8.8-10.4 deg) and
            # stays up, the striker slides down its face to the floor.
            checks.check(m + "struck_max_tilt", ev["struck_max"], kind="max", tolerance=TOPPLED,
                         reference=yev["struck_max"], unit="deg", wall_s=wall,
                         note="must stay below 45 deg (YADE: 10.4 deg young 1e8, 8.8 deg 4e8)")
        elif variant.startswith("fine"):
            checks.check(m + "struck_t45", ev["struck45"], kind="rel", reference=yev["struck45"],
                         tolerance=TOL_T, unit="s", wall_s=wall,
                         note="YADE rigid-limit extrapolation 0.2298 s (young 1e8: 0.2228, 4e8: 0.2263)")
            checks.check(m + "struck_t80", ev["struck80"], kind="rel", reference=yev["struck80"],
                         tolerance=TOL_T, unit="s", wall_s=wall)
        else:
            # Coarse (220-tet) pieces reach 45 deg 7-9 % late: a mesh effect (4 mm mesh +5.1 %,
            # report-size pieces -3.0 %), not a stiffness one (E 5e6..1e10 within 2 %). The
            # time is checked on the report-size pieces (long tier); here it is recorded.
            for k, key in (("struck45", "struck_t45"), ("struck80", "struck_t80")):
                rel = ev[k] / yev[k] - 1.0 if ev[k] is not None and yev[k] else float("nan")
                checks.info(m + key + "_vs_yade", rel, unit="-", reference=yev[k], wall_s=wall,
                            note="coarse pieces, recorded not checked: see README (mesh effect)")
        checks.check(m + "hit_t1", ev["hit"], kind="rel", reference=yev["hit"], tolerance=TOL_HIT,
                     unit="s", wall_s=wall, note="struck piece first tilts 1 deg")
        checks.check(m + "falling_t45", ev["falling45"], kind="rel", reference=yev["falling45"],
                     tolerance=TOL_T, unit="s", wall_s=wall)
        meta = dict(title=f"Two shogi pieces 30 mm apart, mu = {mu} ({variant}): tilt, qdemsph vs YADE",
                    xlabel="t (s)", ylabel="tilt (deg)")
        fig = f"yade_shogi_{variant}_mu{mu}"
        checks.series(fig, "qdemsph struck", t, a1, style="line", **meta)
        checks.series(fig, "qdemsph falling", t, a0, style="line", **meta)
        k = max(1, len(ty) // 400)
        checks.series(fig, "YADE struck", ty[::k], y1[::k], style="line", **meta)
        checks.series(fig, "YADE falling", ty[::k], y0[::k], style="line", **meta)
        ts, _, s1, _ = yade(mu, "_stiff4")
        k = max(1, len(ts) // 400)
        checks.series(fig, "YADE struck, 4 x young", ts[::k], s1[::k], style="line", **meta)
    # Effect of friction. Struck piece: YADE stays up at 0.1 and falls at 0.5.
    (q1, y1), (q5, y5) = res[0.1], res[0.5]
    flips = q1["struck_max"] < TOPPLED and q5["struck45"] is not None
    checks.check(f"{variant}.friction.struck_topples_only_at_mu05", 1.0 if flips else 0.0, kind="min",
                 tolerance=1.0, unit="bool", note="YADE: stays up at mu 0.1, falls at mu 0.5")
    # Falling piece: higher friction delays its 45 deg time (YADE +7.1 %).
    if q1["falling45"] and q5["falling45"]:
        dq = q5["falling45"] / q1["falling45"] - 1.0
        dy = y5["falling45"] / y1["falling45"] - 1.0
        checks.check(f"{variant}.friction.falling_t45_change", dq, kind="abs", reference=dy,
                     tolerance=TOL_FRICTION, unit="-",
                     note="(t45(mu 0.5) - t45(mu 0.1)) / t45(mu 0.1); YADE +7.09 % (young 1e8), +7.14 % (4e8), +7.2 % extrapolated")
    else:
        checks.check(f"{variant}.friction.falling_t45_change", None, kind="abs", reference=0.072,
                     tolerance=TOL_FRICTION, unit="-")
    return res


def test_geometry_matches_yade(qdemsph, checks, case_out):
    """The overridden scene against YADE's shogi_two.py parameters (provenance)."""
    run = must(qdemsph.run, SCENE, case_out / "t0", sets=MATCH + ["run.end_time=1e-5"])
    with h5py.File(run.out / "fields.h5", "r") as f:
        p0 = np.asarray(f["mesh/points"], dtype=float)
        tets = np.asarray(f["mesh/tets"], dtype=np.int64)
        body = np.asarray(f["mesh/body"])
    g = geometry(p0, body, tets)
    prov = json.loads((YADE / "shogi_two_mu0.5_pitch30mm.provenance.json").read_text())["params"]
    mass = prov["mass_kg"]
    checks.check("geometry.mass_tilted", g["mass_tilted"], kind="rel", reference=mass, tolerance=1e-3, unit="kg")
    checks.check("geometry.mass_struck", g["mass_struck"], kind="rel", reference=mass, tolerance=1e-3, unit="kg")
    # Pivot to the struck piece's back face at the base: YADE pitch - T = 20.3 mm.
    gap = g["pivot_y"] - g["struck_back_y"]
    checks.check("geometry.pivot_to_struck_face", gap, kind="abs", reference=prov["pitch_m"] - T,
                 tolerance=2e-5, unit="m", note="YADE: pitch 30 mm between base centres, pivot at T/2")
    checks.check("geometry.pivot_y", g["pivot_y"], kind="abs", reference=-0.5 * T, tolerance=2e-5, unit="m")
    t, (a0, a1), _, _ = tilt_history(run.out / "fields.h5", [TILT0, 0.0])
    checks.check("geometry.initial_tilt", a0[0], kind="abs", reference=prov["tilt0_deg"], tolerance=0.01, unit="deg")
    checks.info("geometry.edge_clearance", g["pivot_z"], unit="m",
                note="0.2 mm = D_DEM above the floor (YADE: on the floor, edge contact sinks 0.2-0.6 mm)")
    checks.require()


def test_pair_vs_yade_coarse(qdemsph, checks, case_out):
    run_variant("coarse_E5e6", qdemsph, checks, case_out)
    checks.require()


@pytest.mark.full
@pytest.mark.parametrize("variant", ["coarse_E1e9", "fine_E5e6", "coarse_E1e10"])
def test_pair_vs_yade_full(variant, qdemsph, checks, case_out):
    run_variant(variant, qdemsph, checks, case_out)
    checks.require()
