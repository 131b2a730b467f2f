"""Hard case: a cantilever on a mesh with sliver elements (make_mesh.py). The stability limit
the solver reports must equal the one computed here from the mesh (smallest altitude / P-wave
speed with the Kelvin-Voigt correction, i.e. set by the worst sliver); runs at 0.5 and 0.99 x
that limit must complete with the energy balance kept. See README.md."""
from pathlib import Path

import numpy as np

from harness import must

HERE = Path(__file__).resolve().parent
E, NU, RHO, ETA = 1.0e6, 0.3, 1000.0, 5.0  # scene.yaml


def read_msh22(path):
    lines = Path(path).read_text().split("\n")
    i = lines.index("$Nodes")
    n = int(lines[i + 1])
    pts = np.array([[float(v) for v in lines[i + 2 + k].split()[1:4]] for k in range(n)])
    j = lines.index("$Elements")
    m = int(lines[j + 1])
    tets = np.array([[int(v) - 1 for v in lines[j + 2 + k].split()[-4:]] for k in range(m)])
    return pts, tets


def min_altitude(pts, tets):
    a, b, c, d = (pts[tets[:, k]] for k in range(4))
    vol = np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6.0
    alt = np.full(len(tets), np.inf)
    for k in range(4):
        f = np.delete(tets, k, axis=1)
        area = 0.5 * np.linalg.norm(np.cross(pts[f[:, 1]] - pts[f[:, 0]], pts[f[:, 2]] - pts[f[:, 0]]), axis=1)
        alt = np.minimum(alt, 3.0 * vol / area)
    return alt, vol


def test_sliver_mesh(qdemsph, checks, case_out):
    pts, tets = read_msh22(HERE / "sliver_beam.msh")
    alt, vol = min_altitude(pts, tets)
    h = 0.05
    checks.info("min_volume_over_mean", float(vol.min() / vol.mean()), unit="-")
    checks.info("min_altitude_over_h", float(alt.min() / h), unit="-")
    cp = np.sqrt(E * (1 - NU) / (RHO * (1 + NU) * (1 - 2 * NU)))
    lmin = alt.min()
    z = (ETA / E) * cp / lmin
    dt_ref = lmin / cp * (np.sqrt(1 + z * z) - z)
    energies = {}
    for f in (0.5, 0.99):
        run = must(qdemsph.run, HERE / "scene.yaml", case_out / f"safety_{f}", sets=[f"run.dt_safety={f}"])
        m = f"x{f}."
        checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0,
                     unit="bool", note=f"status={run.status} {run.summary.get('error', '')}")
        checks.check(m + "dt_critical_vs_mesh", float(run.summary["dt_critical"]), kind="rel", reference=dt_ref,
                     tolerance=1e-6, unit="s", note="limit set by the worst sliver: min altitude / c_p (KV-corrected)")
        checks.check(m + "dt_over_limit", float(run.summary["dt"]) / dt_ref, kind="max", tolerance=f * (1 + 1e-9),
                     unit="-")
        p = run.probes()
        scale = float(np.max(np.abs(p["potential"])))
        checks.check(m + "energy_balance_rel", float(np.max(np.abs(p["total"])) / scale), kind="max",
                     tolerance=1e-4, unit="-", wall_s=run.solver_wall_s,
                     note="|kinetic + strain + gravity potential + dissipated| / max |potential|")
        energies[f] = p
        checks.info(m + "steps", run.summary.get("steps", np.nan), unit="steps")
    for f, p in energies.items():
        checks.series("hard_sliver", f"dt = {f} x limit", p["time"], p["tip_z"], style="line",
                      title="Sliver-mesh cantilever under gravity: tip deflection", xlabel="t (s)", ylabel="uz (m)")
    checks.require()
