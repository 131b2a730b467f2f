"""qdemsph against a rigid-body solution and YADE (Polyhedra, Debian yade 2023.02a) for a king
piece leaning against a fixed block and sliding down it (the ladder problem; issue 5: how
much friction slows sliding contacts between leaning pieces). Tilt against time for mu 0.1,
0.3 and 0.5 (floor and block), the times at which the tilt reaches 80 and 85 deg, the effect
of friction on them, the energy lost by 85 deg. Stored YADE runs:
references/yade/results/shogi_leaning_mu*.csv at five stiffnesses. See README.md."""
import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from harness import must
from harness.paths import REPO
from harness.shogi import crossing, tilt_history

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scene.yaml"
YADE = REPO / "references" / "yade" / "results"
sys.path.insert(0, str(HERE))
import rigid_ladder  # noqa: E402

TILT0 = 76.0
D_DEM = 0.0002
T = 0.0097
MUS = (0.1, 0.3, 0.5)
LEVELS = (80.0, 85.0)
# YADE runs (tag: young): 1e7 is the chain's stiffness (shogi_chain_n40, _n20_mu03_dt2x).
YADE_RUNS = {"_soft10": 1e7, "": 1e8, "_stiff4": 4e8, "_stiff16": 1.6e9, "_stiff64": 6.4e9}
YADE_STIFFEST = "_stiff64"
# Times against the rigid solution: +-5 % (README.md): the coarse pieces' lumped vertex
# masses raise the inertia about the foot by ~4 % (+2 % in time, yade_shogi), and YADE's two
# stiffest runs, which converge on the rigid solution, still differ by 2.5-4 % at mu 0.3-0.5;
# where those two runs lie further from the rigid time (t80 at mu 0.3 and 0.5, up to 7 %:
# the slow start just past the static limit), their largest deviation (tol_t).
TOL_T = 0.05
YADE_CONVERGED = ("_stiff16", "_stiff64")
# Friction effect (t85(mu) - t85(0.1)) / t85(0.1) against the rigid one: mu 0.3 +11.2 %
# (+-3 points), mu 0.5 +68.8 % (+-10 points, 15 % of the effect): YADE's two stiffest runs
# differ by 2.6 (mu 0.3) and 4 (mu 0.5) points and lie within 7.4 points of the rigid effect.
TOL_EFFECT = {0.3: 0.03, 0.5: 0.10}

VARIANTS = {
    "base": [],                                                   # the chain's settings
    "mesh3": ["bodies.0.mesh.mesh_size=0.003"],                   # finer piece
    "plane": ["bodies.1.mesh.origin=[-0.0287, -1.0, 0]",          # analytic wall, block away
              "walls.1={point: [0, -0.0356301348, 0], normal: [0, 1, 0], mu: MU}"],
    "finer_block": ["bodies.1.mesh.cells=[24, 6, 24]"],
    "restitution1": ["contact.restitution=1.0"],                  # no contact damping
    "stiffness0.5": ["contact.stiffness_factor=0.5"],
    "stiffness0.02": ["contact.stiffness_factor=0.02"],
    "E1e8": ["materials.boxwood.E=1.0e8"],                        # 20 x stiffer pieces
}


def yade(mu, tag):
    name = YADE / f"shogi_leaning_mu{mu}{tag}"
    with open(f"{name}.csv") as f:
        data = np.array(list(csv.reader(f))[1:], dtype=float)
    return data[:, 0], data[:, 1], json.loads(Path(f"{name}.provenance.json").read_text())


def yade_t(mu, tag, level):
    return yade(mu, tag)[2]["results"][f"t_tilt_{level:g}_s"]


def tol_t(mu, level, rigid):
    """Tolerance of a time against the rigid one: TOL_T, or more where YADE's converged runs
    themselves differ more from the rigid time (the reference's spread bounds the claim)."""
    return max(TOL_T, max(abs(yade_t(mu, tag, level) / rigid - 1.0) for tag in YADE_CONVERGED))


def run_mu(qdemsph, case_out, variant, mu):
    sets = [s.replace("MU", str(mu)) for s in VARIANTS[variant]]
    run = must(qdemsph.run, SCENE, case_out / f"{variant}_mu{mu}",
               sets=sets + [f"contact.mu={mu}", f"walls.0.mu={mu}"])
    t, (a,), _, _ = tilt_history(run.out / "fields.h5", [TILT0])
    ev = {lv: crossing(t, a, lv) for lv in LEVELS}
    p = run.probes()
    lost = None
    if ev[85.0] is not None:  # energy the contacts took by 85 deg (friction slip + dashpots)
        lost = float(np.interp(ev[85.0], p["time"], p["contact_dissipated"] + p["dissipated"]))
    return run, t, a, ev, lost


def run_variant(variant, qdemsph, checks, case_out, checked):
    """Three runs (mu 0.1, 0.3, 0.5). checked: times and friction effect against the rigid
    solution are checks (else recorded as info)."""
    t85 = {}
    for mu in MUS:
        run, t, a, ev, lost = run_mu(qdemsph, case_out, variant, mu)
        wall = run.solver_wall_s
        m = f"{variant}.mu{mu}."
        checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min",
                     tolerance=1.0, unit="bool")
        rig, sep, (tr, ar) = rigid_ladder.slide(mu, TILT0, LEVELS)
        for lv in LEVELS:
            ref = rig[lv][0]
            if checked:
                checks.check(m + f"t{lv:g}", ev[lv], kind="rel", reference=ref, tolerance=tol_t(mu, lv, ref),
                             unit="s", wall_s=wall,
                             note=f"tilt {lv:g} deg; rigid-body solution (rigid_ladder.py); tolerance: 5 % or "
                                  "YADE's two stiffest runs' deviation from it")
            else:
                checks.info(m + f"t{lv:g}", ev[lv], unit="s", reference=ref, wall_s=wall,
                            note=f"tilt {lv:g} deg; reference: rigid-body solution")
            y = yade_t(mu, YADE_STIFFEST, lv)
            if ev[lv] is not None:
                checks.info(m + f"t{lv:g}_vs_yade_stiffest", ev[lv] / y - 1.0, unit="-", reference=y,
                            note="YADE young 6.4e9, dt 1.25e-6")
        if mu >= 0.3 and ev[85.0] is not None:  # below 0.3 the time hardly depends on mu
            checks.info(m + "effective_mu", rigid_ladder.effective_mu(ev[85.0], TILT0), unit="-", reference=mu,
                        note="mu with which the rigid piece reaches 85 deg at qdemsph's time; YADE: "
                        + ", ".join(f"{y:.2g}: {rigid_ladder.effective_mu(yade_t(mu, tag, 85), TILT0):.3f}"
                                    for tag, y in YADE_RUNS.items()))
        checks.info(m + "energy_lost_by_85deg", lost, unit="J", reference=rig[85.0][1],
                    note="qdemsph contact_dissipated + dissipated; reference: rigid friction work")
        checks.info(m + "wall", wall, unit="s", wall_s=wall)
        t85[mu] = ev[85.0]
        meta = dict(title=f"Leaning king piece sliding down a block, mu = {mu}: tilt",
                    xlabel="t (s)", ylabel="tilt (deg)")
        fig = f"yade_shogi_leaning_{variant}_mu{mu}"
        checks.series(fig, f"qdemsph ({variant})", t, a, style="line", **meta)
        checks.series(fig, "rigid body", tr, ar, style="line", **meta)
        for tag in ("_soft10", "", "_stiff64"):
            ty, ay, _ = yade(mu, tag)
            keep = ty <= 0.08
            checks.series(fig, f"YADE young {YADE_RUNS[tag]:.1e}", ty[keep], ay[keep], style="line", **meta)
    # Friction effect on the whole slide: (t85(mu) - t85(0.1)) / t85(0.1).
    r85 = {mu: rigid_ladder.slide(mu, TILT0, LEVELS)[0][85.0][0] for mu in MUS}
    for mu in (0.3, 0.5):
        ref = r85[mu] / r85[0.1] - 1.0
        val = t85[mu] / t85[0.1] - 1.0 if t85[mu] and t85[0.1] else None
        name = f"{variant}.friction.t85_change_mu0.1_to_{mu}"
        note = "rigid " + f"{ref:+.3f}; YADE " + ", ".join(
            f"{y:.2g}: {yade_t(mu, tag, 85) / yade_t(0.1, tag, 85) - 1.0:+.3f}" for tag, y in YADE_RUNS.items())
        if checked:
            checks.check(name, val, kind="abs", reference=ref, tolerance=TOL_EFFECT[mu], unit="-", note=note)
        else:
            checks.info(name, val, unit="-", reference=ref, note=note)
    if checked:
        fig = "yade_shogi_leaning_friction"
        meta = dict(title="Time to 85 deg against friction: qdemsph, rigid body, YADE by stiffness",
                    xlabel="mu", ylabel="t85 (s)")
        checks.series(fig, "qdemsph", MUS, [t85[mu] for mu in MUS], style="points", **meta)
        checks.series(fig, "rigid body", MUS, [r85[mu] for mu in MUS], style="line", **meta)
        for tag, y in YADE_RUNS.items():
            checks.series(fig, f"YADE young {y:.1e}", MUS, [yade_t(mu, tag, 85) for mu in MUS],
                          style="line", **meta)


def test_geometry_matches_yade(qdemsph, checks, case_out):
    """The scene at t = 0 against shogi_leaning.py's provenance: mass, foot on YADE's pivot line
    D_DEM above the floor, apex D_DEM from the block's face, initial tilt."""
    import h5py

    run = must(qdemsph.run, SCENE, case_out / "t0", sets=["run.end_time=1e-5"])
    prov = yade(0.5, "")[2]["params"]
    with h5py.File(run.out / "fields.h5", "r") as f:
        p0 = np.asarray(f["mesh/points"], dtype=float)
        tets = np.asarray(f["mesh/tets"], dtype=np.int64)
        body = np.asarray(f["mesh/body"])
    x = [p0[tets[:, i]] for i in range(4)]
    vol = np.abs(np.einsum("ij,ij->i", x[1] - x[0], np.cross(x[2] - x[0], x[3] - x[0]))) / 6.0
    mass = vol[body[tets[:, 0]] == 0].sum() * prov["density"]
    piece, block = p0[body == 0], p0[body == 1]
    foot = piece[piece[:, 2] < piece[:, 2].min() + 1e-6]
    checks.check("geometry.mass", mass, kind="rel", reference=prov["mass_kg"], tolerance=1e-3, unit="kg")
    checks.check("geometry.foot_y", foot[:, 1].mean(), kind="abs", reference=-0.5 * T, tolerance=2e-6,
                 unit="m", note="YADE's pivot x = T/2 (qdemsph leans toward -y)")
    checks.check("geometry.foot_z", piece[:, 2].min(), kind="abs", reference=D_DEM, tolerance=2e-6, unit="m")
    checks.check("geometry.apex_y", piece[:, 1].min(), kind="abs", reference=-prov["block_face_x_m"],
                 tolerance=2e-6, unit="m", note="YADE's block face is at the apex")
    checks.check("geometry.apex_to_block", piece[:, 1].min() - block[:, 1].max(), kind="abs",
                 reference=D_DEM, tolerance=2e-6, unit="m", note="touching: D_DEM gap")
    _, (a,), _, _ = tilt_history(run.out / "fields.h5", [TILT0])
    checks.check("geometry.initial_tilt", a[0], kind="abs", reference=prov["tilt0_deg"], tolerance=0.01, unit="deg")
    checks.require()


def test_leaning_vs_rigid_and_yade(qdemsph, checks, case_out):
    run_variant("base", qdemsph, checks, case_out, checked=True)
    checks.require()


@pytest.mark.full
@pytest.mark.parametrize("variant", [v for v in VARIANTS if v != "base"])
def test_leaning_variants(variant, qdemsph, checks, case_out):
    """One parameter changed at a time; recorded, not checked (README.md)."""
    run_variant(variant, qdemsph, checks, case_out, checked=False)
    checks.require()
