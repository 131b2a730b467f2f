"""Shogi pieces (BENCHMARKS.md section 5; report Figs. 9-10): a tilted piece toppling onto
another at mu = 0.1 and 0.5 (higher friction must be slower), one piece dropped onto two
(edge-edge dominated). The 40-piece chain is verification/cases/yade_shogi_chain (YADE's
arrangement). See README.md."""
from pathlib import Path

import numpy as np
import pytest

from harness import must

HERE = Path(__file__).resolve().parent


def fall_time(t, z):
    """First time the centre height drops below 60 % of its initial value (a piece lying flat
    has its centre at ~1/3 of the standing height)."""
    below = np.flatnonzero(z < 0.6 * z[0])
    return float(t[below[0]]) if below.size else np.nan


@pytest.mark.parametrize("mesh", ["coarse", pytest.param("report", marks=pytest.mark.full)])
def test_pair_friction_slows_toppling(mesh, qdemsph, checks, case_out):
    sets = [] if mesh == "coarse" else ["bodies.0.mesh.mesh_size=null", "bodies.1.mesh.mesh_size=null"]
    times = {}
    for mu in (0.1, 0.5):
        run = must(qdemsph.run, HERE / "scene_pair.yaml", case_out / f"mu{mu}", sets=sets + [f"contact.mu={mu}"])
        p = run.probes()
        t, z = p["time"], p["struck_z"]
        m = f"{mesh}.mu{mu}."
        checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0, unit="bool")
        times[mu] = fall_time(t, z)
        checks.check(m + "struck_fall_time", times[mu], kind="range", tolerance=[0.05, 0.34], unit="s",
                     wall_s=run.solver_wall_s, note="struck piece's centre below 60 % of its initial height")
        checks.info(m + "wall", run.solver_wall_s, unit="s", wall_s=run.solver_wall_s)
        checks.series(f"contact_shogi_pair_{mesh}", f"struck piece, mu = {mu}", t, z, style="line",
                      title=f"Shogi pair ({mesh} mesh): struck piece centre height", xlabel="t (s)", ylabel="z (m)")
    checks.check(f"{mesh}.slowdown_mu05_over_mu01", times[0.5] / times[0.1], kind="min", tolerance=1.0 + 1e-9,
                 unit="-", note="report Fig. 9: higher friction topples more slowly")
    checks.require()


def test_one_on_two_edge_impact(qdemsph, checks, case_out):
    run = must(qdemsph.run, HERE / "scene_one_on_two.yaml", case_out / "run")
    p = run.probes()
    c = run.summary.get("contact", {})
    checks.check("one_on_two.completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0, unit="bool")
    # It lands on the ridges (0.0322 m + half its thickness + D_DEM) and stays up there.
    checks.check("one_on_two.final_height", float(p["falling_z"][-1]), kind="range", tolerance=[0.034, 0.039],
                 unit="m", note="resting on the two pieces' top ridges, not fallen through")
    checks.check("one_on_two.max_overlap", c.get("max_overlap_ever", np.nan), kind="max", tolerance=0.0004,
                 unit="m", note="2 D_DEM")
    checks.info("one_on_two.wall", run.solver_wall_s, unit="s", wall_s=run.solver_wall_s)
    checks.series("contact_shogi_one_on_two", "falling piece", p["time"], p["falling_z"], style="line",
                  title="One piece onto two: centre height", xlabel="t (s)", ylabel="z (m)")
    checks.require()
