#!/usr/bin/python3
"""Linear-elastic cantilever with FEniCSx (Debian dolfinx 0.5.2): the reference for qdemsph.

Problem (BENCHMARKS.md section 1): face x = 0 clamped (u = 0), uniform dead traction
(0, 0, tz) on the face x = L, no body force, small-strain Hooke law (E, nu). Solved with a
direct solver (PETSc preonly + MUMPS LU), Lagrange P1 or P2 vector elements, on

  --mesh FILE.msh        a Gmsh MSH 4.1 ASCII tetrahedral mesh (what `qdemsph mesh` writes), or
  --box NX NY NZ         a structured beam [0,L]x[0,B]x[0,H] built here: `--split qdem12`
                         (12 tets per hex around a centre vertex, like qdemsph's box) or
                         `--split dolfinx` (dolfinx.mesh.create_box, 6 tets per hex).

Writes into --out DIR:
  displacement_p<d>.csv  vertex, x, y, z, ux, uy, uz at the mesh vertices (vertex = row of
                         the input mesh in node-tag order, i.e. tag - 1 for qdemsph meshes)
  result_p<d>.json       tip deflection (integral mean of uz over the x = L face), its ratio to
                         Euler-Bernoulli and Timoshenko, dofs, cells, wall times
  provenance.json        tool and versions, script hash, mesh file and sha256, date, per-degree runs

Run with /usr/bin/python3 (Debian's interpreter has dolfinx). Serial only; do not use mpirun.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import hashlib
import json
import os
import platform
import sys
import time
from pathlib import Path

# Reproducible, comparable timings on a shared 2-core machine: one thread unless told otherwise.
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import logging  # noqa: E402

import numpy as np  # noqa: E402

logging.basicConfig(level=logging.WARNING)

sys.path.insert(0, str(Path(__file__).resolve().parent))
import meshio41  # noqa: E402
from beam_theory import beam_theory  # noqa: E402


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def build_mesh(args, comm):
    """Return (dolfinx mesh, original vertex coordinates (N,3), mesh description dict)."""
    import ufl
    from dolfinx import mesh as dmesh

    if args.mesh:
        points, tets, tags = meshio41.read_msh41(args.mesh)
        desc = {"mesh": str(Path(args.mesh)), "mesh_sha256": sha256_file(args.mesh),
                "mesh_kind": "msh41", "n_vertices": int(len(points)), "n_tets": int(len(tets))}
    elif args.split == "qdem12":
        points, tets = meshio41.box_mesh([args.length, args.width, args.height], args.box)
        h = hashlib.sha256(np.ascontiguousarray(points).tobytes() + np.ascontiguousarray(tets).tobytes())
        desc = {"mesh": f"box {args.box[0]}x{args.box[1]}x{args.box[2]} split qdem12 (built by meshio41.box_mesh)",
                "mesh_sha256": h.hexdigest(), "mesh_kind": "box-qdem12",
                "n_vertices": int(len(points)), "n_tets": int(len(tets))}
    else:
        msh = dmesh.create_box(comm, [np.zeros(3), np.array([args.length, args.width, args.height])],
                               list(args.box), dmesh.CellType.tetrahedron)
        orig = np.empty_like(msh.geometry.x)
        orig[np.asarray(msh.geometry.input_global_indices, dtype=np.int64)] = msh.geometry.x
        desc = {"mesh": f"box {args.box[0]}x{args.box[1]}x{args.box[2]} dolfinx.mesh.create_box",
                "mesh_sha256": None, "mesh_kind": "box-dolfinx",
                "n_vertices": int(len(orig)), "n_tets": int(msh.topology.index_map(3).size_local)}
        return msh, orig, desc
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.tetrahedron, 1))
    # Gmsh and dolfinx share the vertex order of linear tets (permutation is the identity).
    msh = dmesh.create_mesh(comm, tets.astype(np.int64), points, domain)
    return msh, points, desc


def solve(args):
    from mpi4py import MPI
    import ufl
    import dolfinx
    from dolfinx import fem, mesh as dmesh
    from dolfinx.fem.petsc import LinearProblem
    from petsc4py import PETSc

    comm = MPI.COMM_WORLD
    if comm.size != 1:
        sys.exit("cantilever.py is serial: run it without mpirun")
    t0 = time.perf_counter()
    msh, orig_points, desc = build_mesh(args, comm)
    x = msh.geometry.x
    L = args.length if args.length is not None else float(x[:, 0].max())
    if args.length is None:
        args.length = L
    lo = x.min(axis=0)
    B, H = (x[:, 1].max() - lo[1]), (x[:, 2].max() - lo[2])
    tol = 1e-9 * max(L, 1.0)

    V = fem.VectorFunctionSpace(msh, ("Lagrange", args.degree))
    fdim = msh.topology.dim - 1
    clamp = dmesh.locate_entities_boundary(msh, fdim, lambda p: np.abs(p[0] - lo[0]) <= tol)
    tip = dmesh.locate_entities_boundary(msh, fdim, lambda p: np.abs(p[0] - L) <= tol)
    if len(clamp) == 0 or len(tip) == 0:
        sys.exit(f"no boundary facets at x = {lo[0]} (clamp: {len(clamp)}) or x = {L} (tip: {len(tip)})")
    order = np.argsort(tip)
    tags = dmesh.meshtags(msh, fdim, tip[order].astype(np.int32), np.ones(len(tip), dtype=np.int32))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                         fem.locate_dofs_topological(V, fdim, clamp), V)

    E, nu = args.E, args.nu
    mu = E / (2.0 * (1.0 + nu))
    lmbda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)

    def eps(w):
        return ufl.sym(ufl.grad(w))

    def sigma(w):
        return 2.0 * mu * eps(w) + lmbda * ufl.tr(eps(w)) * ufl.Identity(3)

    traction = fem.Constant(msh, np.array([0.0, 0.0, args.traction], dtype=PETSc.ScalarType))
    a = ufl.inner(sigma(u), eps(v)) * ufl.dx
    rhs = ufl.inner(traction, v) * ds(1)
    problem = LinearProblem(a, rhs, bcs=[bc], petsc_options={
        "ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"})
    t1 = time.perf_counter()
    uh = problem.solve()
    t2 = time.perf_counter()
    reason = problem.solver.getConvergedReason()
    if reason < 0:
        sys.exit(f"PETSc solve failed (KSP converged reason {reason})")

    area = fem.assemble_scalar(fem.form(1.0 * ds(1)))
    w_int = fem.assemble_scalar(fem.form(uh[2] * ds(1)))
    energy = fem.assemble_scalar(fem.form(0.5 * ufl.inner(sigma(uh), eps(uh)) * ufl.dx))
    tip_w = w_int / area

    # Vertex values: the first 4 cell dofs of P1/P2 sit on the cell's vertices, in the same
    # local order as the (P1) geometry dofmap; map geometry nodes back to input rows.
    ncell = msh.topology.index_map(3).size_local
    gdofs = msh.geometry.dofmap.array.reshape(ncell, -1)[:, :4]
    cdofs = V.dofmap.list.array.reshape(ncell, -1)[:, :4]
    rows = np.asarray(msh.geometry.input_global_indices, dtype=np.int64)[gdofs.ravel()]
    vals = uh.x.array.reshape(-1, 3)
    disp = np.full((len(orig_points), 3), np.nan)
    disp[rows] = vals[cdofs.ravel()]
    dof_xyz = V.tabulate_dof_coordinates()[cdofs.ravel()]
    if np.isnan(disp).any() or np.abs(dof_xyz - orig_points[rows]).max() > 1e-10 * max(L, 1.0):
        sys.exit("internal error: vertex/dof mapping does not reproduce the input coordinates")

    P = abs(args.traction) * area
    d_eb, d_t = beam_theory(E, nu, L - lo[0], B, H, P)
    result = {
        "degree": args.degree, "tip_deflection": float(tip_w), "tip_area": float(area),
        "load": float(P), "d_euler_bernoulli": d_eb, "d_timoshenko": d_t,
        "ratio_eb": abs(tip_w) / d_eb, "ratio_timoshenko": abs(tip_w) / d_t,
        "strain_energy": float(energy), "max_abs_u": float(np.abs(disp).max()),
        "dofs": int(V.dofmap.index_map.size_global * V.dofmap.index_map_bs),
        "n_vertices": desc["n_vertices"], "n_tets": desc["n_tets"],
        "setup_s": t1 - t0, "solve_s": t2 - t1, "total_s": time.perf_counter() - t0,
        "threads": int(os.environ.get("OMP_NUM_THREADS", "0")),
        "E": E, "nu": nu, "length": L, "width": float(B), "height": float(H), "traction_z": args.traction,
    }
    versions = {"dolfinx": dolfinx.__version__, "petsc": ".".join(map(str, PETSc.Sys.getVersion())),
                "python": platform.python_version()}
    return result, disp, orig_points, desc, versions


def write_outputs(args, result, disp, points, desc, versions):
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    d = args.degree
    with open(out / f"displacement_p{d}.csv", "w") as f:
        f.write("vertex,x,y,z,ux,uy,uz\n")
        for i, (p, u) in enumerate(zip(points, disp)):
            f.write(f"{i},{p[0]:.17g},{p[1]:.17g},{p[2]:.17g},{u[0]:.17g},{u[1]:.17g},{u[2]:.17g}\n")
    (out / f"result_p{d}.json").write_text(json.dumps(result, indent=2) + "\n")
    script = Path(__file__).resolve()
    prov_path = out / "provenance.json"
    prov = {}
    if prov_path.exists():
        try:
            prov = json.loads(prov_path.read_text())
        except json.JSONDecodeError:
            prov = {}
        if prov.get("mesh_sha256") != desc["mesh_sha256"]:
            prov = {}  # a different mesh: start over
    prov.update({
        "tool": "FEniCSx (Debian python3-dolfinx)", "versions": versions,
        "script": "references/fenicsx/" + script.name, "script_sha256": sha256_file(script),
        **desc,
        "problem": {"E": args.E, "nu": args.nu, "length": result["length"], "traction_z": args.traction,
                    "clamp": "u = 0 on x = min", "tip": "integral mean of uz over x = L face"},
        "solver": "PETSc KSP preonly + LU (MUMPS)",
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "host": platform.node(),
    })
    prov.setdefault("runs", {})[f"p{d}"] = {
        "dofs": result["dofs"], "tip_deflection": result["tip_deflection"],
        "solve_s": result["solve_s"], "date": prov["date"]}
    prov_path.write_text(json.dumps(prov, indent=2) + "\n")


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--mesh", help="Gmsh MSH 4.1 ASCII tetrahedral mesh")
    src.add_argument("--box", nargs=3, type=int, metavar=("NX", "NY", "NZ"), help="structured beam cells")
    p.add_argument("--split", choices=["qdem12", "dolfinx"], default="qdem12", help="tet split for --box")
    p.add_argument("--degree", type=int, choices=[1, 2], default=1)
    p.add_argument("--E", type=float, default=1.0e7)
    p.add_argument("--nu", type=float, default=0.3)
    p.add_argument("--length", type=float, default=None,
                   help="x of the loaded face (default: max x of the mesh; 1.0 for --box)")
    p.add_argument("--width", type=float, default=0.1, help="--box only")
    p.add_argument("--height", type=float, default=0.1, help="--box only")
    p.add_argument("--traction", type=float, default=-100.0, help="z traction on the tip face (Pa)")
    p.add_argument("--out", required=True)
    args = p.parse_args(argv)
    if args.box and args.length is None:
        args.length = 1.0
    return args


def main(argv=None):
    args = parse_args(argv)
    result, disp, points, desc, versions = solve(args)
    write_outputs(args, result, disp, points, desc, versions)
    print(f"P{args.degree} {desc['mesh']}: {desc['n_tets']} tets, {result['dofs']} dofs, "
          f"tip w = {result['tip_deflection']:.6e} (w/d_EB = {result['ratio_eb']:.4f}), "
          f"solve {result['solve_s']:.2f} s")


if __name__ == "__main__":
    main()
