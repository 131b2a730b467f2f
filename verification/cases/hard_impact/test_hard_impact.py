"""Hard case: 50 m/s impact of a spinning, tilted cube onto a fixed block (contact).
No tunnelling, no blow-up: the cube's centre never goes below the struck face, it rebounds,
the overlap stays bounded and the total energy never grows. See README.md."""
from pathlib import Path

import numpy as np

from harness import must

HERE = Path(__file__).resolve().parent


def test_impact_50_m_per_s(qdemsph, checks, case_out):
    run = must(qdemsph.run, HERE / "scene.yaml", case_out / "run")
    p = run.probes()
    # Mechanical energy: the budget's total less what the contact dashpots and slip dissipated
    # (probes.csv's total includes it since the contact energy joined the budget).
    t, z, e = p["time"], p["cube_z"], p["total"] - p.get("contact_dissipated", 0.0)
    c = run.summary.get("contact", {})
    checks.check("completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0,
                 unit="bool", note=f"status={run.status} {run.summary.get('error', '')}")
    checks.check("min_centre_height", float(z.min()), kind="min", tolerance=0.0, unit="m",
                 note="struck face z = 0; a tunnelled cube's centre ends below it (half size 0.025 m)")
    vz_end = float(np.polyfit(t[-20:], z[-20:], 1)[0])
    checks.check("rebound_vz", vz_end, kind="min", tolerance=2.5, unit="m/s",
                 note="impact at -50 m/s; the cube must come back up (5 % of the impact speed at least)")
    checks.check("max_overlap", c.get("max_overlap_ever", np.nan), kind="max", tolerance=0.005, unit="m",
                 note="bounded penetration: below 5 D_DEM (D_DEM = 1 mm)")
    checks.check("energy_growth_rel", float((e.max() - e[0]) / e[0]), kind="max", tolerance=0.01, unit="-",
                 note="contact with restitution 0.5 may only remove energy")
    checks.info("energy_end_over_start", float(e[-1] / e[0]), unit="-")
    checks.info("budget_drift_rel", float(np.max(np.abs(p["total"] - p["total"][0])) / p["total"][0]), unit="-",
                note="max |total - total(0)| / total(0), contact energy included: velocity Verlet's error at the impact")
    checks.info("steps", run.summary.get("steps", np.nan), unit="steps", wall_s=run.solver_wall_s)
    checks.series("hard_impact", "cube centre z", t, z, style="line", title="50 m/s impact: cube centre height",
                  xlabel="t (s)", ylabel="z (m)")
    checks.require()
