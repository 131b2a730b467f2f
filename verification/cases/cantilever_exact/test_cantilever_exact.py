"""qdemsph (linear law, static) against FEniCSx P1 on the identical mesh: the same discrete
problem, so the nodal displacements must agree to the static solver's tolerance.

The FEniCSx P1 solve runs live here (quick tier): it proves the reference script still runs."""
from pathlib import Path

import numpy as np
import pytest

from harness import cantilever as cl
from harness import paths  # noqa: F401  (makes meshio41 importable)
from harness.fenicsx import solve_cantilever
from harness import must

import meshio41

HERE = Path(__file__).resolve().parent
SCENES = {"box_20x2x2": HERE / "scene_box.yaml", "gmsh_beam": HERE / "scene_gmsh.yaml"}
REL_TOL = 1.0e-6  # max nodal |du| / max |u|: see README.md


@pytest.mark.parametrize("variant", sorted(SCENES))
def test_qdemsph_matches_fenicsx_p1(variant, qdemsph, checks, case_out):
    scene = SCENES[variant]
    msh = must(qdemsph.mesh, scene, case_out / "mesh")["beam"]
    run = must(qdemsph.run, scene, case_out / "run")
    ref, table, _ = must(solve_cantilever, case_out / "fenicsx", degree=1, mesh=msh,
                         E=cl.E, nu=cl.NU, traction=cl.TRACTION, length=cl.LENGTH)
    m = f"{variant}."
    static = run.summary.get("static", {})
    checks.check(m + "static_converged", 1.0 if (run.status == "converged" and static.get("converged")) else 0.0,
                 kind="min", tolerance=1.0, unit="bool", backend=run.backend,
                 note=f"status={run.status}, static={static}")
    checks.info(m + "static_iterations", static.get("iterations", np.nan), unit="steps", backend=run.backend)
    checks.info(m + "qdemsph_wall", run.solver_wall_s, unit="s", wall_s=run.solver_wall_s, backend=run.backend)
    checks.info(m + "fenicsx_p1_solve", ref["solve_s"], unit="s", wall_s=ref["solve_s"], backend="fenicsx-p1")

    mpts, mtets, _ = meshio41.read_msh41(msh)
    if variant == "gmsh_beam":  # qdemsph must keep every tet of the imported mesh
        _, src_tets, _ = meshio41.read_msh41(HERE / "beam.msh")
        checks.check(m + "exported_tets", len(mtets), kind="abs", reference=len(src_tets), tolerance=0, unit="tets")
    points, tets, disp, _t = must(run.final_fields)
    checks.check(m + "mesh_mismatch", cl.match_vertices(points, mpts, cl.LENGTH), kind="max",
                 tolerance=1e-12, unit="1/L", note="fields.h5 /mesh/points vs the exported .msh, row by row")
    checks.check(m + "tet_mismatch", 0.0 if np.array_equal(np.sort(tets, 1), np.sort(mtets, 1)) else 1.0,
                 kind="max", tolerance=0.0, unit="bool")

    u_ref = table[:, 4:7]
    if table.shape[0] != disp.shape[0]:
        pytest.fail(f"vertex count differs: qdemsph {disp.shape[0]}, FEniCSx {table.shape[0]}", pytrace=False)
    umax = float(np.abs(u_ref).max())
    checks.check(m + "fenicsx_tip_ratio_eb", abs(ref["tip_deflection"]) / ref["d_euler_bernoulli"],
                 kind="range", tolerance=[0.3, 1.05], unit="-",
                 note="sanity: the reference is a bent beam, not a zero or blown-up field")
    checks.check(m + "max_nodal_diff_rel", float(np.abs(disp - u_ref).max() / umax), kind="max",
                 tolerance=REL_TOL, unit="-", wall_s=run.solver_wall_s, backend=run.backend)
    w_q = cl.tip_deflection(points, tets, disp)
    checks.check(m + "tip_deflection", w_q, kind="rel", reference=ref["tip_deflection"], tolerance=REL_TOL,
                 unit="m", wall_s=run.solver_wall_s, backend=run.backend)
    tip_vertices = cl.region_mask(points, 0, 0.999999999, 1.000000001)
    probe = must(lambda: cl.last_probe(run.probes(), "tip"))
    probe_ref = u_ref[tip_vertices].mean(axis=0)
    checks.check(m + "tip_probe_z", probe[2], kind="rel", reference=float(probe_ref[2]), tolerance=REL_TOL,
                 unit="m", backend=run.backend, note="probe = mean displacement of the vertices in the region")

    edge = np.flatnonzero((np.abs(points[:, 1]) < 1e-9) & (np.abs(points[:, 2]) < 1e-9))
    edge = edge[np.argsort(points[edge, 0])]
    fig = f"cantilever_exact_{variant}"
    meta = dict(title=f"Deflection along the edge y = z = 0 ({variant})", xlabel="x (m)", ylabel="uz (m)")
    checks.series(fig, "FEniCSx P1", points[edge, 0], u_ref[edge, 2], style="line", **meta)
    checks.series(fig, f"qdemsph ({run.backend})", points[edge, 0], disp[edge, 2], style="points", **meta)
    checks.require()
