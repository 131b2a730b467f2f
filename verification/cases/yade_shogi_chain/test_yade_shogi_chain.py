"""qdemsph against YADE (Polyhedra, Debian yade 2023.02a) for the 40-piece shogi chain
(references/yade/shogi_chain.py; stored runs results/shogi_chain_n40, _n20_stiff4,
_n20_dt2x): every piece falls, the fall time of each piece (tilt 45 deg, both codes on one
axis) and the front speed. The chain run is long (long tier); the quick tier checks that
the scene is YADE's (geometry, mass, the first piece's tilt and spin) and shows the committed
GPU runs of the chain and its variants (ci/gpu/chain_runs.sh). See README.md."""
import json
import math
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from harness import must
from harness.paths import REPO
from harness.shogi import crossing

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scene_chain.yaml"
YADE = REPO / "references" / "yade" / "results"
sys.path.insert(0, str(HERE))
import make_yade_chain  # noqa: E402  (the scene's parameters: N, PITCH, TILT0, OMEGA0, TOP_Z)
from chain_analysis import FRONT_TILT, chain_tilts, front_speed  # noqa: E402
import rigid_chain  # noqa: E402  (the rigid-body reference)

FIT = (10, 38)  # YADE's front-speed window for 40 pieces (pieces n/4 .. n-2)
WINDOWS = {"5_18": (5, 18), "5_35": (5, 35)}  # the 20-piece variants' window; the brief's
# qdemsph's undamped 20-piece chain (recorded GPU run c20_e1: YADE's pieces, push 20 rad/s,
# mu 0.5) against YADE's converged chain (young 1.6e9; README.md "YADE's stiffest chains"). The
# tolerance is computed from the stored references, the rule of issue 5: YADE's spread (6.4e9
# and half the step against 1.6e9) plus the contact-law difference, which the rigid model
# measures (README.md "Frictionless chain": its piece-piece contacts 40 x softer than the
# floor's, as YADE's volumetric vertex impacts are, against equal stiffness; both from YADE's
# start). (YADE run, its spread runs; rigid pair)
YADE_CONVERGED = ("n20_stiff160", ("n20_stiff640", "n20_stiff160_halfdt"))
RIGID_CONTACT_LAW = ("n20_mu0.5_e1_w20_k1e5_kpp0.025_nospin", "n20_mu0.5_e1_w20_k1e5_nospin")
# The chain and its variants run on a GPU (ci/gpu/chain_runs.sh; README.md, "GPU runs").
GPU_RUNS = REPO / "references" / "benchmarks" / "gpu" / "2026-11-25_h100_chain.json"
# The same chain and the mu 0.3 variant at the contact stiffness default of 0.1 (the runs above
# used 0.5, the default until contact_ladder showed it loses static friction).
GPU_RUNS_K01 = REPO / "references" / "benchmarks" / "gpu" / "2026-11-25_h100_chain_k01.json"
GPU_VARIANTS = {"c40": "40 pieces, 6 mm mesh", "c20_E4": "20 pieces, 6 mm, 4 x E",
                "c20_mu03": "20 pieces, 6 mm, piece-piece mu 0.3", "f20_4": "20 pieces, 4 mm mesh",
                "f20_3": "20 pieces, 3 mm mesh"}
# Rigid-body reference (rigid_chain.py; stored runs references/rigid/results, README.md
# "Rigid-body reference"). Pendulum: one piece released at rest at 25 deg (balance 20.4 deg)
# pivots on its front bottom edge to 45 deg; the time against the rigid pendulum's ODE within
# 5e-4 at the chain's k 1e5 N/m (penalty pivot: 5e-4 at 1e4, 8e-5 at 1e5).
RIGID = REPO / "references" / "rigid" / "results"
PEND = (25.0, 45.0)
PEND_K = (1e4, 1e5)
TOL_PEND = 5e-4
# Energy at mu 0, e 1 (3 pieces, 0.3 s, k 2.5e4 N/m): drift of kinetic + gravity + contact
# springs within 1e-3 m g H (measured 3e-4 at the stored runs' 40 steps per contact period).
TOL_ENERGY = 1e-3
# Convergence of the stored 20-piece front speed (pieces 5..18): (run, against, tolerance,
# what). Restitution 0.3: 4 x k and dt / 2 within 2 % of k 1e5 N/m, 40 steps per contact
# period (measured 0.1 %). Undamped: k 4e5 -> 1.6e6 within 2 % (measured -0.7 %), dt / 2 at
# k 1e5 within 2 % (-0.4 %); the undamped k 1e5 run lies 3.9 % above the 1.6e6 one (bouncing
# contacts scatter the undamped front; k 2.5e4 and 4e5 lie within 1 % of 1.6e6): within 5 %.
# The undamped 40-piece chain (pieces 10..38): k 4e5 within 2 % of 1e5 (measured -1.0 %).
RIGID_CONVERGENCE = (("n20_mu0.5_e0.3_w12_k4e5", "n20_mu0.5_e0.3_w12_k1e5", 0.02, "4 x k"),
                     ("n20_mu0.5_e0.3_w12_k1e5_dt2", "n20_mu0.5_e0.3_w12_k1e5", 0.02, "dt / 2"),
                     ("n20_mu0.5_e1_w20_k1.6e6", "n20_mu0.5_e1_w20_k4e5", 0.02, "undamped, 4 x k"),
                     ("n20_mu0.5_e1_w20_k1e5_dt2", "n20_mu0.5_e1_w20_k1e5", 0.02, "undamped, dt / 2"),
                     ("n20_mu0.5_e1_w20_k1e5", "n20_mu0.5_e1_w20_k1.6e6", 0.05, "undamped, k / 16"),
                     ("n40_mu0.5_e1_w20_k4e5", "n40_mu0.5_e1_w20_k1e5", 0.02, "undamped, 40 pieces, 4 x k"))
# qdemsph's recorded GPU runs against the rigid front speed of the same restitution: +-15 %
# (README.md, "Rigid-body reference": the reference's spread, the contact damping laws' and
# the 6 mm mesh's differences). (rigid run, qdemsph run, checked)
TOL_VS_RIGID = 0.15
RIGID_VS_QDEMSPH = (("n40_mu0.5_e0.3_w12_k1e5", "c40", True), ("n20_mu0.5_e0.3_w12_k1e5", "c20", False),
                    ("n20_mu0.3_e0.3_w12_k1e5", "c20_mu03all", False), ("n20_mu0.5_e1_w20_k1.6e6", "c20_e1", True),
                    ("n20_mu0.3_e1_w16_k1e5", "c20_e1_mu03all", False), ("n40_mu0.5_e1_w20_k4e5", None, False))


def rigid(name):
    return json.loads((RIGID / f"rigid_chain_{name}.provenance.json").read_text())


def yade(tag):
    return json.loads((YADE / f"shogi_chain_{tag}.provenance.json").read_text())


def test_scene_matches_yade(qdemsph, checks, case_out):
    """The scene at t = 0 against YADE's shogi_chain provenance: mass, pitch, the first
    piece's pivot, tilt and spin about its pivot edge."""
    run = must(qdemsph.run, SCENE, case_out / "t0", sets=["run.end_time=1e-5"])
    prov = yade("n40")["params"]
    with h5py.File(run.out / "fields.h5", "r") as f:
        p0 = np.asarray(f["mesh/points"], dtype=float)
        tets = np.asarray(f["mesh/tets"], dtype=np.int64)
        body = np.asarray(f["mesh/body"])
        v0 = np.asarray(f["steps"]["000000"]["velocity"], dtype=float)
    x = [p0[tets[:, i]] for i in range(4)]
    vol = np.abs(np.einsum("ij,ij->i", x[1] - x[0], np.cross(x[2] - x[0], x[3] - x[0]))) / 6.0
    mass = np.bincount(body[tets[:, 0]], weights=vol) * prov["density"]
    checks.check("scene.mass_max_dev", float(np.max(np.abs(mass / prov["mass_kg"] - 1.0))), kind="max",
                 tolerance=1e-3, unit="-", note=f"all 40 pieces against YADE's {prov['mass_kg']:.6g} kg")
    # Standing pieces: base centre at y = -i * pitch.
    base_y = [p0[(body == b) & (p0[:, 2] < 0.0003), 1].mean() for b in range(1, make_yade_chain.N)]
    checks.check("scene.pitch", float(np.mean(np.diff(base_y))) * -1.0, kind="rel", reference=prov["pitch_m"],
                 tolerance=1e-6, unit="m")
    # Piece 0: pivot (lowest edge) at y = -T/2 (YADE: front bottom edge at T/2 from the base
    # centre), its tilt, and a rigid spin omega0 about the pivot edge.
    t = prov["h_w_t_m"][2]
    q, v = p0[body == 0], v0[body == 0]
    low = q[:, 2] < q[:, 2].min() + 1e-6
    pivot = np.array([0.0, q[low, 1].mean(), q[low, 2].mean()])
    checks.check("scene.pivot_y", pivot[1], kind="abs", reference=-0.5 * t, tolerance=2e-6, unit="m")
    r = q - pivot
    omega = float(np.sum(r[:, 1] * v[:, 2] - r[:, 2] * v[:, 1]) / np.sum(r[:, 1] ** 2 + r[:, 2] ** 2))
    resid = float(np.max(np.abs(v - np.cross([omega, 0.0, 0.0], r))))
    checks.check("scene.spin_about_pivot", omega, kind="rel", reference=make_yade_chain.OMEGA0, tolerance=1e-6,
                 unit="rad/s", note=f"YADE base run {prov['omega0_rad_per_s']} rad/s, its 4 x young run "
                                    f"{yade('n20_stiff4')['params']['omega0_rad_per_s']} rad/s (README)")
    checks.check("scene.spin_rigid_residual", resid, kind="max", tolerance=1e-8, unit="m/s",
                 note="initial velocity minus omega x (x - pivot)")
    _, tilts = chain_tilts(run.out)
    checks.check("scene.initial_tilt", tilts[0, 0], kind="abs", reference=prov["tilt0_deg"], tolerance=0.01,
                 unit="deg")
    checks.require()


def test_recorded_gpu_chain(checks):
    """The committed GPU runs (H100, 2026-11-25): the whole 40-piece chain (every piece must
    have fallen) and the 20-piece variants, their fall times beside YADE's and their front
    speeds over pieces 5..18 against YADE's 20-piece window; the undamped 20-piece run against
    YADE's converged chain, within YADE's spread plus the contact-law effect (README.md)."""
    runs = {r["run"]: r for r in json.loads(GPU_RUNS.read_text())}
    c40 = runs["c40"]
    checks.check("gpu_run.c40_fallen", c40["fallen"], kind="min", tolerance=make_yade_chain.N, unit="pieces",
                 wall_s=c40["wall_s"], backend=c40["backend"], note="the whole 40-piece chain, 3.6 s on an H100")
    yv = {tag: front_speed(yade(tag)["results"]["fall_time_s"], make_yade_chain.PITCH, 5, 18)
          for tag in ("n40", "n20_stiff4", "n20_stiff16", "n20_dt2x")}
    meta = dict(title="Shogi chain on the GPU: fall time of each piece, qdemsph variants vs YADE",
                xlabel="piece", ylabel="t (s)")
    for name, label in GPU_VARIANTS.items():
        r = runs[name]
        v = r["front_speed_m_s"]["5..18"]["qdemsph"]
        checks.info(f"gpu_run.{name}.front_speed_5_18", v, unit="m/s", reference=yv["n40"],
                    wall_s=r["wall_s"], backend=r["backend"],
                    note=f"{label}; {v / yv['n40'] - 1:+.1%} vs YADE base, {v / yv['n20_stiff16'] - 1:+.1%} vs "
                         f"YADE 16 x young")
        f = [float("nan") if x is None else x for x in r["fall_time_s"]]
        checks.series("yade_shogi_chain_gpu_fall_times", f"qdemsph {label}", range(len(f)), f, style="points",
                      **meta)
    k01 = {r["run"]: r for r in json.loads(GPU_RUNS_K01.read_text())}
    checks.check("gpu_run_k01.c40_fallen", k01["c40"]["fallen"], kind="min", tolerance=make_yade_chain.N,
                 unit="pieces", wall_s=k01["c40"]["wall_s"], backend=k01["c40"]["backend"],
                 note="the whole chain at the contact stiffness default 0.1")
    v01 = {n: r["front_speed_m_s"]["5..18"]["qdemsph"] for n, r in k01.items()}
    for n, v in v01.items():
        checks.info(f"gpu_run_k01.{n}.front_speed_5_18", v, unit="m/s", reference=yv["n40"],
                    wall_s=k01[n]["wall_s"], backend=k01[n]["backend"],
                    note=f"stiffness_factor 0.1; {v / yv['n40'] - 1:+.1%} vs YADE base")
    # YADE's friction effect grows with its contact stiffness (yade_shogi_leaning: at young 1e7
    # friction barely slows a piece sliding down a face).
    y03 = {base: front_speed(yade(f"n20_mu03_{base[4:]}")["results"]["fall_time_s"], make_yade_chain.PITCH, 5, 18)
           / yv[base] - 1 for base in ("n20_dt2x", "n20_stiff4", "n20_stiff16")}
    checks.info("gpu_run_k01.mu03_speedup", v01["c20_mu03all"] / v01["c20"] - 1, unit="-",
                note=f"front speed at mu 0.3 over mu 0.5 (pieces and floor, as YADE): YADE "
                     f"{y03['n20_dt2x']:+.1%} at young 1e7 (n20_mu03_dt2x over n20_dt2x), "
                     f"{y03['n20_stiff4']:+.1%} at 4e7, {y03['n20_stiff16']:+.1%} at 1.6e8")
    fy = lambda tag: front_speed(yade(tag)["results"]["fall_time_s"], make_yade_chain.PITCH, 5, 18)  # noqa: E731
    fr = lambda n: front_speed(rigid(n)["results"]["fall_time_s"], make_yade_chain.PITCH, 5, 18)  # noqa: E731
    ref = fy(YADE_CONVERGED[0])
    spread = max(abs(fy(t) / ref - 1) for t in YADE_CONVERGED[1])
    law = fr(RIGID_CONTACT_LAW[0]) / fr(RIGID_CONTACT_LAW[1]) - 1
    checks.check("gpu_run_k01.c20_e1.front_speed_vs_yade_converged", v01["c20_e1"], kind="rel", reference=ref,
                 tolerance=spread + abs(law), unit="m/s", wall_s=k01["c20_e1"]["wall_s"],
                 backend=k01["c20_e1"]["backend"],
                 note=f"pieces 5..18, 20 pieces undamped, push 20 rad/s; YADE young 1.6e9 {ref:.4f} m/s; tolerance "
                      f"{spread:.1%} YADE's spread + {law:+.1%} contact-law effect (rigid model, piece-piece "
                      f"contacts 40 x softer: YADE's ratio; README.md)")
    f = [float("nan") if x is None else x for x in k01["c40"]["fall_time_s"]]
    checks.series("yade_shogi_chain_gpu_fall_times", "qdemsph 40 pieces, stiffness_factor 0.1",
                  range(len(f)), f, style="points", **meta)
    for tag, label in (("n40", "YADE young 1e7, omega0 5"), ("n20_stiff16", "YADE 16 x young, omega0 12")):
        f = [float("nan") if v is None else v for v in yade(tag)["results"]["fall_time_s"]]
        checks.series("yade_shogi_chain_gpu_fall_times", label, range(len(f)), f, style="points", **meta)
    meta = dict(title="Shogi chain: front speed (pieces 5..18) against the pieces' mesh size",
                xlabel="mesh size (mm)", ylabel="front speed (m/s)")
    h = {"c40": 6, "f20_4": 4, "f20_3": 3}
    checks.series("yade_shogi_chain_mesh", "qdemsph (GPU runs)", list(h.values()),
                  [runs[n]["front_speed_m_s"]["5..18"]["qdemsph"] for n in h], style="line", **meta)
    for tag, label in (("n40", "YADE young 1e7"), ("n20_stiff16", "YADE 16 x young")):
        checks.series("yade_shogi_chain_mesh", label, [3, 6], [yv[tag]] * 2, style="hline", **meta)
    checks.require()


@pytest.mark.full
def test_chain_vs_yade(qdemsph, checks, case_out):
    run = must(qdemsph.run, SCENE, case_out / "run")
    wall = run.solver_wall_s
    checks.check("chain.completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0,
                 unit="bool")
    t, tilts = chain_tilts(run.out)
    fall = [crossing(t, a, FRONT_TILT) for a in tilts]
    fallen = sum(f is not None for f in fall)
    checks.check("chain.fallen", fallen, kind="min", tolerance=make_yade_chain.N, unit="pieces", wall_s=wall,
                 note="tilt past 45 deg; YADE: all 40")
    checks.info("chain.wall", wall, unit="s", wall_s=wall)
    base = yade("n40")
    pitch = make_yade_chain.PITCH
    speed = front_speed(fall, pitch, *FIT)
    ref = base["results"]["front_speed_m_per_s"]
    # Recorded, not checked: YADE's 40-piece run is at young 1e7, 20 % above its own converged
    # chain (README.md); the check against converged YADE is the quick tier's
    # gpu_run_k01.c20_e1.front_speed_vs_yade_converged.
    checks.info("chain.front_speed", speed, unit="m/s", reference=ref, wall_s=wall,
                note="pieces 10..38 (YADE's window); YADE young 1e7 0.4576 m/s (not converged in stiffness)")
    rig = rigid(RIGID_VS_QDEMSPH[0][0])["results"]
    checks.check("chain.front_speed_vs_rigid", speed, kind="rel", reference=rig["front_speed_m_per_s"],
                 tolerance=TOL_VS_RIGID, unit="m/s", wall_s=wall,
                 note="pieces 10..38; rigid-body reference at the scene's restitution 0.3 and push (README.md)")
    if speed is not None:
        checks.info("chain.front_speed_over_sqrt_gh", speed / math.sqrt(9.81 * 0.032), unit="-",
                    note="YADE 0.817")
        half = (FIT[0] + FIT[1]) // 2
        checks.info("chain.front_speed_first_half", front_speed(fall, pitch, FIT[0], half), unit="m/s",
                    note="steadiness; YADE 0.4544")
        checks.info("chain.front_speed_second_half", front_speed(fall, pitch, half, FIT[1]), unit="m/s",
                    note="steadiness; YADE 0.4563")
    for name, (lo, hi) in WINDOWS.items():
        yv = {}
        for tag in ("n40", "n20_stiff4", "n20_stiff16", "n20_dt2x"):
            f = yade(tag)["results"]["fall_time_s"]
            if hi < len(f):
                yv[tag] = front_speed(f, pitch, lo, hi)
        checks.info(f"chain.front_speed_{name}", front_speed(fall, pitch, lo, hi), unit="m/s",
                    note="YADE " + ", ".join(f"{k} {v:.4f}" for k, v in yv.items()))
    rest = [float(a[-1]) for a in tilts[:-1]]
    checks.info("chain.rest_tilt_min", min(rest), unit="deg", note="pieces 0..38 at the end; YADE 62-68 deg")
    checks.info("chain.rest_tilt_max", max(rest), unit="deg")
    meta = dict(title="40-piece shogi chain: fall time (tilt 45 deg) of each piece, qdemsph vs YADE",
                xlabel="piece", ylabel="t (s)")
    nan = [float("nan") if f is None else f for f in fall]
    checks.series("yade_shogi_chain_fall_times", "qdemsph (coarse pieces, omega0 12 rad/s)",
                  range(make_yade_chain.N), nan, style="points", **meta)
    for tag, label in (("n40", "YADE young 1e7, omega0 5"), ("n20_stiff4", "YADE 4 x young, omega0 12"),
                       ("n20_stiff16", "YADE 16 x young, omega0 12"), ("n20_dt2x", "YADE 2 x dt, omega0 5")):
        f = [float("nan") if v is None else v for v in yade(tag)["results"]["fall_time_s"]]
        checks.series("yade_shogi_chain_fall_times", label, range(len(f)), f, style="points", **meta)
    f = [float("nan") if v is None else v for v in rig["fall_time_s"]]
    checks.series("yade_shogi_chain_fall_times", "rigid body, e 0.3, omega0 12", range(len(f)), f, style="points",
                  **meta)
    meta = dict(title="40-piece shogi chain: tilt of every fifth piece, qdemsph", xlabel="t (s)",
                ylabel="tilt (deg)")
    k = max(1, len(t) // 800)
    for b in range(0, make_yade_chain.N, 5):
        checks.series("yade_shogi_chain_tilts", f"qdemsph piece {b}", t[::k], tilts[b][::k], style="line", **meta)
    checks.require()


def test_rigid_mass_properties(checks):
    """The rigid reference's piece: mass, centre height and inertia about the width axis (a
    planar integration over the height) against the tetrahedra of the exact polyhedron
    (yade_shogi_leaning/rigid_ladder.py) and YADE's mass."""
    sys.path.insert(0, str(HERE.parent / "yade_shogi_leaning"))
    import rigid_ladder
    for name, v, ref in (("mass", rigid_chain.M, rigid_ladder.M), ("zc", rigid_chain.ZC, rigid_ladder.ZC),
                         ("inertia", rigid_chain.I, rigid_ladder.I)):
        checks.check(f"rigid.{name}", v, kind="rel", reference=ref, tolerance=1e-9, unit="SI",
                     note="against rigid_ladder.mass_properties (polyhedron tetrahedra)")
    checks.check("rigid.mass_vs_yade", rigid_chain.M, kind="rel", reference=yade("n40")["params"]["mass_kg"],
                 tolerance=1e-9, unit="kg")
    checks.require()


def polyhedron_inertia():
    """The piece's inertia from the polyhedron's tetrahedra (rigid_ladder.py), independent of
    rigid_chain.mass_properties."""
    sys.path.insert(0, str(HERE.parent / "yade_shogi_leaning"))
    import rigid_ladder
    return rigid_ladder.I


def pendulum_error(k, inertia=None):
    c = rigid_chain.Chain(1, mu=0.5, e=1.0, k=k, tilt0=PEND[0], omega0=0.0, inertia=inertia)
    r = c.run(0.2, tail=0.0, levels=(PEND[1],))
    return r["fall_time_s"][0] / rigid_chain.pendulum_time(*PEND, inertia=polyhedron_inertia())[0] - 1.0


def test_rigid_pendulum(checks):
    """One piece of the rigid model released at rest at 25 deg pivots on its front bottom edge:
    its time to 45 deg against the rigid pendulum (ODE about the fixed edge, rtol 1e-12, with
    the polyhedron's inertia) as the penalty stiffness grows. Negative control: 2 % more
    inertia in the model (1 % in time) must fail the tolerance."""
    ref, ratio = rigid_chain.pendulum_time(*PEND, inertia=polyhedron_inertia())
    checks.info("rigid.pendulum.t45_ode", ref, unit="s",
                note=f"largest friction ratio needed on the way {ratio:.3f} (< mu 0.5: no slip)")
    err = {k: pendulum_error(k) for k in PEND_K}
    for k in PEND_K[:-1]:
        checks.info(f"rigid.pendulum.error_k{k:g}", err[k], unit="-")
    checks.check(f"rigid.pendulum.error_k{PEND_K[-1]:g}", abs(err[PEND_K[-1]]), kind="max", tolerance=TOL_PEND,
                 unit="-", note="relative time error at the stored runs' k")
    checks.check("rigid.pendulum.error_falls_with_k", abs(err[PEND_K[-1]]) / abs(err[PEND_K[0]]), kind="max",
                 tolerance=0.5, unit="-", note="10 x k")
    wrong = pendulum_error(PEND_K[-1], inertia=1.02 * rigid_chain.I)
    checks.check("rigid.pendulum.control_inertia_x1.02", abs(wrong), kind="min", tolerance=TOL_PEND, unit="-",
                  note="a 2 % inertia error must be caught")
    checks.require()


def test_rigid_energy(checks):
    """Frictionless, undamped (mu 0, e 1): three pieces for 0.3 s (piece 0 pushed into piece 1,
    impacts, sliding on the floor); kinetic + gravity + contact-spring energy stays within
    TOL_ENERGY m g H of its start."""
    c = rigid_chain.Chain(3, mu=0.0, e=1.0, k=2.5e4)
    r = c.run(0.3, record_every=1e-3, stop_when_fallen=False)
    e = r["energy"]
    scale = rigid_chain.M * rigid_chain.G * rigid_chain.H
    spin = 0.5 * (rigid_chain.I + rigid_chain.M * float(rigid_chain.FOOT @ rigid_chain.FOOT)) * rigid_chain.OMEGA0 ** 2
    checks.check("rigid.energy.max_drift", float(np.max(np.abs(e - e[0]))) / scale, kind="max",
                 tolerance=TOL_ENERGY, unit="m g H", note=f"m g H = {scale:.4e} J; piece 0's initial spin about "
                 f"its edge {spin:.2e} J")
    checks.check("rigid.energy.contact_active", float(np.max(r["tilt_deg"][:, 1])), kind="min", tolerance=1.0,
                 unit="deg", note="piece 1 was pushed (the contacts were exercised)")
    checks.require()


def test_rigid_reference(checks):
    """The stored rigid-body runs (references/rigid/results; rigid_chain.py --all): every
    piece falls, the front speed converges in contact stiffness and time step, and qdemsph's
    recorded GPU runs (stiffness_factor 0.1) against the rigid front speed of the same
    restitution (README.md, "Rigid-body reference"); YADE's beside it."""
    for name in rigid_chain.RUNS:
        r = rigid(name)
        checks.check(f"rigid.{name}.fallen", r["results"]["n_fallen"], kind="min", tolerance=r["params"]["n"],
                     unit="pieces", wall_s=r["wall_s"])
    speed = {name: rigid(name)["results"]["front_speed_m_per_s"] for name in rigid_chain.RUNS}
    for run, ref, tol, what in RIGID_CONVERGENCE:
        checks.check(f"rigid.convergence.{run}", speed[run], kind="rel", reference=speed[ref], tolerance=tol,
                     unit="m/s", note=f"{what}: front speed (YADE's window) against {ref}")
    for s in ("_e0.3_w12", "_e1_w20"):
        checks.info(f"rigid.convergence.n20_mu0.5{s}_k2.5e4", speed[f"n20_mu0.5{s}_k2.5e4"], unit="m/s",
                    reference=speed[f"n20_mu0.5{s}_k1e5"], note="k / 4")
    gpu = {r["run"]: r for r in json.loads(GPU_RUNS_K01.read_text())}
    yv = {tag: front_speed(yade(tag)["results"]["fall_time_s"], make_yade_chain.PITCH, 5, 18)
          for tag in ("n40", "n20_stiff4", "n20_stiff16", "n20_mu03_stiff16")}
    for name, q, checked in RIGID_VS_QDEMSPH:
        r = rigid(name)
        v = r["results"]["front_speed_m_per_s"]
        lo, hi = r["results"]["fit_pieces"]
        if lo == 10:
            note = f"pieces 10..38; YADE n40 {yade('n40')['results']['front_speed_m_per_s']:.4f}"
        else:
            note = "pieces 5..18; YADE " + ", ".join(f"{t} {x:.4f}" for t, x in yv.items())
        checks.info(f"rigid.{name}.front_speed", v, unit="m/s", wall_s=r["wall_s"], note=note)
        if q is None:
            continue
        qv = gpu[q]["front_speed_m_s"][f"{lo}..{hi}"]["qdemsph"]
        metric = f"gpu_run_k01.{q}.front_speed_vs_rigid"
        note = f"qdemsph {q} (6 mm pieces) against rigid_chain {name}, pieces {lo}..{hi}"
        if checked:
            checks.check(metric, qv, kind="rel", reference=v, tolerance=TOL_VS_RIGID, unit="m/s",
                         wall_s=gpu[q]["wall_s"], backend=gpu[q]["backend"], note=note)
        else:
            checks.info(metric, qv, unit="m/s", reference=v, note=note)
    meta = dict(title="Shogi chain on the GPU: fall time of each piece, qdemsph variants vs YADE",
                xlabel="piece", ylabel="t (s)")
    for name, label in (("n40_mu0.5_e0.3_w12_k1e5", "rigid body, e 0.3, omega0 12"),
                        ("n40_mu0.5_e1_w20_k4e5", "rigid body, e 1, omega0 20")):
        f = [float("nan") if x is None else x for x in rigid(name)["results"]["fall_time_s"]]
        checks.series("yade_shogi_chain_gpu_fall_times", label, range(len(f)), f, style="points", **meta)
    checks.require()
