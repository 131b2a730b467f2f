#!/usr/bin/python3
"""The elastic gate of Antoci et al. 2007 under still water, static, 2-D, with FEniCSx
(Debian dolfinx 0.5.2): the reference for verification/cases/sph_elastic_gate (issue 7).

Problem. The gate is the strip x = 0..T, y = Y0..Y0 + L (T = 0.005 m, L = 0.079 m, Y0 = 0.001
m; the floor is y = 0), its top edge y = Y0 + L clamped (u = 0), its upstream face x = 0
loaded by still water of level H on the x < 0 side, p = rho_w g (H - y) for y < H (rho_w
1000, g 9.81). Rubber: E = 11.96 MPa, nu = 0.40 (BENCHMARKS.md section 7). Lagrange P2
triangles (`create_rectangle`, NX x NY cells split into 2 triangles each), direct solver
(PETSc preonly + MUMPS LU), one thread.

Cases, each in plane stress (a slab with free faces in z, what qdemsph's gate is) and plane
strain (a gate spanning its tank):
  linear      small-strain Hooke law, the load on the undeformed face (plane stress:
              lambda* = 2 mu lambda / (lambda + 2 mu))
  svk         St. Venant-Kirchhoff, psi = lambda/2 tr(E)^2 + mu E:E (plane stress: the exact
              condensation S33 = 0, i.e. lambda*; the slab's stretch in z is
              lambda3 = sqrt(1 + 2 E33), E33 = -lambda tr(E) / (lambda + 2 mu))
  nh          compressible neo-Hookean, psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2
              (plane strain: F33 = 1; plane stress: the stretch in z lambda3 = 1 + theta is
              a second field, DG1, and S33 = 0 holds weakly as the energy's stationarity in it)
  same lambda, mu (the small-strain E, nu) for all; each nonlinear law with the load
  follower     the pressure of the deformed height y = Y + u_y acts normal to the deformed face
               on its deformed area: p(y) lambda3 J F^-T e_x per reference area (Nanson;
               lambda3 = 1 in plane strain)
  dead         p(Y) e_x on the reference face (the linear case's load)
The nonlinear solves are load-stepped in the level H (0.01 ... 0.04, then the levels asked
for; a step is halved when Newton fails), each from the last converged state.

Beam theory beside it (numpy, per row): the linear Euler-Bernoulli tip (the formula of
quasi_static_tip in verification/cases/sph_elastic_gate/test_sph_elastic_gate.py, with E for
plane stress and E / (1 - nu^2) for plane strain) and Timoshenko's; for the nonlinear rows the
elastica (inextensible Euler-Bernoulli beam with large rotations, the same load type) loaded on
the upstream face like the FE model (elastica_x, _y) and on the axis (elastica_axis_x: the
large-rotation counterpart of quasi_static_tip). See elastica_tips.

Output (--out, default references/fenicsx/results), lengths in m:
  gate_static.csv   one row per mesh, state, model, load and level: the free tip's (the edge
                    y = Y0) mean horizontal (+: downstream) and vertical (+: up) displacement,
                    the beam-theory tips above, Newton iterations and solve time since the last
                    level
  gate_static.json  provenance (dolfinx/PETSc versions, script and its sha256, meshes, date,
                    machine, wall times), the problem, mesh convergence (largest relative change
                    of the horizontal tip between the two finest meshes), the level at which each
                    model's tip (finest mesh) reaches the experiment's 46.4 mm and each of its
                    tabulated tips, the FE tips over beam theory (finest mesh)

Run: /usr/bin/python3 references/fenicsx/gate_static.py [--meshes 4x64 8x128] [--levels ...]
Serial only; do not use mpirun.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import logging  # noqa: E402

import numpy as np  # noqa: E402

logging.basicConfig(level=logging.WARNING)
# The JIT's build step (setuptools) lowers the root logger's level: filter at the handler.
for _h in logging.getLogger().handlers:
    _h.setLevel(logging.WARNING)

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "verification"))
sys.path.insert(0, str(HERE))
from cantilever import sha256_file  # noqa: E402
from harness import machine  # noqa: E402

# Gate, rubber and water (BENCHMARKS.md section 7; the scenes of sph_elastic_gate).
T_GATE, L_GATE, Y0 = 0.005, 0.079, 0.001
E_RUBBER, NU_RUBBER = 11.96e6, 0.40
RHO_W, G = 1000.0, 9.81
EXP_PEAK_TIP = 0.0464  # m: the experiment's horizontal tip at 0.16 s
# The experiment's horizontal tip (m) at t = 0.04 ... 0.36 s (BENCHMARKS.md section 7).
EXP_T = [0.04, 0.08, 0.12, 0.16, 0.20, 0.24, 0.28, 0.32, 0.36]
EXP_X = [0.0125, 0.0340, 0.0440, 0.0464, 0.0442, 0.0430, 0.0412, 0.0400, 0.0374]

DEFAULT_MESHES = ["4x64", "8x128"]
# Water levels (m): 0.100..0.145 (the range of the experiment's column and of qdemsph's runs),
# widened to 0.050..0.200 so that the level each model needs for each of the experiment's tips
# (12.5..46.4 mm) lies inside the table.
DEFAULT_LEVELS = [round(0.050 + 0.005 * i, 3) for i in range(31)]
RAMP = [0.01, 0.02, 0.03, 0.04]  # levels passed on the way to the first asked-for level
MODELS = [("linear", "dead"), ("svk", "follower"), ("svk", "dead"), ("nh", "follower"), ("nh", "dead")]
STATES = ["stress", "strain"]
FIELDS = ["mesh", "nx", "ny", "dofs", "state", "model", "load", "H", "tip_x", "tip_y", "beam_eb",
          "beam_timoshenko", "elastica_x", "elastica_y", "elastica_axis_x", "newton_its", "solve_s"]


def lame(E, nu):
    mu = E / (2.0 * (1.0 + nu))
    return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu


def beam_tips(H, state, E=E_RUBBER, nu=NU_RUBBER, n=4001):
    """Linear cantilever tips (per unit width; bending modulus E in plane stress, E / (1 - nu^2)
    in plane strain) under p = rho g (H - y)+ on the gate: Euler-Bernoulli (the formula of
    quasi_static_tip in test_sph_elastic_gate.py: a point load P at distance a from the clamp
    gives P a^2 (3L - a) / (6 E I) at the tip) and Timoshenko (plus P a / (k G A), G = E / (2 (1
    + nu)), Cowper's k = 10 (1 + nu) / (12 + 11 nu))."""
    a = np.linspace(0.0, L_GATE, n)
    y = Y0 + L_GATE - a
    p = RHO_W * G * np.clip(H - y, 0.0, None)
    ei = (E if state == "stress" else E / (1.0 - nu**2)) * T_GATE**3 / 12.0
    k = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)
    kga = k * E / (2.0 * (1.0 + nu)) * T_GATE
    eb = float(np.trapz(p * a**2 * (3.0 * L_GATE - a) / (6.0 * ei), a))
    return eb, eb + float(np.trapz(p * a / kga, a))


def _cumtrapz(f, h):
    """Cumulative trapezoid integral from s = 0 along axis 0."""
    c = np.zeros_like(f)
    c[1:] = np.cumsum(0.5 * h * (f[1:] + f[:-1]), axis=0)
    return c


def elastica_tips(levels, state, load, face=True, E=E_RUBBER, nu=NU_RUBBER, n=200):
    """Tips (x, y) of the gate as an inextensible Euler-Bernoulli beam with large rotations
    (the elastica; bending stiffness per unit width E T^3 / 12, E / (1 - nu^2) in plane strain),
    under the still-water load of each level in `levels` (ascending; Newton in the node angles,
    from the last level's shape). theta(s) is the axis' angle from the downward vertical (+:
    downstream), s the arc length from the clamp; EI theta' = M(s), the moment about the axis
    point s of the loads beyond it.
    face=True loads the upstream face like the FE model: the face point lies T/2 upstream of
    the axis; follower: the pressure of the face point's height, normal to the axis, on the
    face's stretched length (1 + kappa T/2) (times the slab's width change 1 - nu kappa T/2 in
    plane stress); dead: p of the reference height along x at the face point, which adds the
    moment (T/2) p sin(theta) per unit length. face=False puts the load on the axis (the large-
    rotation counterpart of quasi_static_tip)."""
    s = np.linspace(0.0, L_GATE, n + 1)
    h = s[1] - s[0]
    ei = (E if state == "stress" else E / (1.0 - nu**2)) * T_GATE**3 / 12.0
    c = 0.5 * T_GATE if face else 0.0
    col = (slice(None), None)
    y_ref = (Y0 + L_GATE - s)[col]

    def rcum(f):
        a = _cumtrapz(f, h)
        return a[-1] - a

    def phi(th, H):  # th: (n + 1, k) angles, k shapes at once
        x = _cumtrapz(np.sin(th), h)
        y = Y0 + L_GATE - _cumtrapz(np.cos(th), h)
        if load == "follower":
            kap = np.gradient(th, h, axis=0)
            area = (1.0 + kap * c) * ((1.0 - nu * kap * c) if state == "stress" else 1.0)
            p = RHO_W * G * np.clip(H - (y - c * np.sin(th)), 0.0, None) * area
            fx, fy, m = p * np.cos(th), p * np.sin(th), 0.0
        else:
            fx = RHO_W * G * np.clip(H - y_ref, 0.0, None) * np.ones_like(th)
            fy, m = np.zeros_like(th), c * fx * np.sin(th)
        moment = rcum(x * fy - y * fx + m) - x * rcum(fy) + y * rcum(fx)
        return _cumtrapz(moment / ei, h)

    th = np.zeros((n + 1, 1))
    eye = 1e-7 * np.eye(n + 1)
    out = []
    for H in levels:
        for _ in range(50):
            r = th - phi(th, H)
            pert = th + eye
            jac = ((pert - phi(pert, H)) - r) / 1e-7  # finite-difference Jacobian, all columns at once
            dth = np.linalg.solve(jac, -r)
            th = th + dth
            if np.abs(dth).max() < 1e-12:
                break
        else:
            sys.exit(f"elastica: no convergence at H = {H}")
        out.append((float(_cumtrapz(np.sin(th), h)[-1, 0]), float(L_GATE - _cumtrapz(np.cos(th), h)[-1, 0])))
    return out


def parse_mesh(name):
    nx, ny = (int(c) for c in name.lower().split("x"))
    if nx < 1 or ny < 1:
        raise argparse.ArgumentTypeError(f"mesh must look like 4x64, got {name!r}")
    return nx, ny


class Gate:
    """One mesh: the function spaces, the clamp, the tip and upstream-face measures."""

    def __init__(self, nx, ny):
        from mpi4py import MPI
        import ufl
        from dolfinx import mesh as dmesh

        self.nx, self.ny = nx, ny
        self.msh = dmesh.create_rectangle(MPI.COMM_WORLD, [np.array([0.0, Y0]), np.array([T_GATE, Y0 + L_GATE])],
                                          [nx, ny], dmesh.CellType.triangle)
        tol = 1e-9
        fdim = 1
        self.clamp = dmesh.locate_entities_boundary(self.msh, fdim, lambda p: np.abs(p[1] - (Y0 + L_GATE)) < tol)
        face = dmesh.locate_entities_boundary(self.msh, fdim, lambda p: np.abs(p[0]) < tol)
        tip = dmesh.locate_entities_boundary(self.msh, fdim, lambda p: np.abs(p[1] - Y0) < tol)
        facets = np.concatenate([face, tip]).astype(np.int32)
        marks = np.concatenate([np.full(len(face), 1), np.full(len(tip), 2)]).astype(np.int32)
        order = np.argsort(facets)
        tags = dmesh.meshtags(self.msh, fdim, facets[order], marks[order])
        md = {"quadrature_degree": 4}
        self.dx = ufl.Measure("dx", domain=self.msh, metadata=md)
        self.ds = ufl.Measure("ds", domain=self.msh, subdomain_data=tags, metadata=md)
        self.X = ufl.SpatialCoordinate(self.msh)


def solve_case(gate, state, model, load, levels, log):
    """Load-step one case through `levels` (ascending); returns a list of per-level dicts."""
    from mpi4py import MPI
    import ufl
    from dolfinx import fem
    from dolfinx.fem.petsc import LinearProblem, NonlinearProblem
    from dolfinx.nls.petsc import NewtonSolver
    from petsc4py import PETSc

    msh, dx, ds, X = gate.msh, gate.dx, gate.ds, gate.X
    lam, mu = lame(E_RUBBER, NU_RUBBER)
    lam_s = 2.0 * mu * lam / (lam + 2.0 * mu)  # plane stress
    lam2 = lam_s if state == "stress" else lam
    H = fem.Constant(msh, PETSc.ScalarType(levels[0]))
    I2 = ufl.Identity(2)
    ex = ufl.as_vector([1.0, 0.0])
    mixed = model == "nh" and state == "stress"

    if mixed:
        el = ufl.MixedElement([ufl.VectorElement("Lagrange", msh.ufl_cell(), 2),
                               ufl.FiniteElement("DG", msh.ufl_cell(), 1)])
        W = fem.FunctionSpace(msh, el)
        V0, _ = W.sub(0).collapse()
        zero = fem.Function(V0)
        dofs = fem.locate_dofs_topological((W.sub(0), V0), 1, gate.clamp)
        bc = fem.dirichletbc(zero, dofs, W.sub(0))
    else:
        W = fem.VectorFunctionSpace(msh, ("Lagrange", 2))
        bc = fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), fem.locate_dofs_topological(W, 1, gate.clamp), W)
    w = fem.Function(W)
    dofs_n = W.dofmap.index_map.size_global * W.dofmap.index_map_bs
    u = ufl.split(w)[0] if mixed else w
    opts = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}

    def p_at(y):
        return RHO_W * G * ufl.max_value(H - y, 0.0)

    tip_len = fem.assemble_scalar(fem.form(1.0 * ds(2)))
    tip_forms = [fem.form(u[0] * ds(2)), fem.form(u[1] * ds(2))]

    def tip():
        return tuple(float(fem.assemble_scalar(f) / tip_len) for f in tip_forms)

    rows = []
    if model == "linear":
        uu, v = ufl.TrialFunction(W), ufl.TestFunction(W)
        eps = lambda q: ufl.sym(ufl.grad(q))  # noqa: E731
        sig = lambda q: 2.0 * mu * eps(q) + lam2 * ufl.tr(eps(q)) * I2  # noqa: E731
        a = ufl.inner(sig(uu), eps(v)) * dx
        rhs = p_at(X[1]) * ufl.dot(ex, v) * ds(1)
        problem = LinearProblem(a, rhs, bcs=[bc], u=w, petsc_options=opts)
        for h in levels:
            H.value = h
            t0 = time.perf_counter()
            problem.solve()
            if problem.solver.getConvergedReason() < 0:
                sys.exit(f"linear solve failed at H = {h}")
            rows.append({"H": h, "tip": tip(), "its": 1, "s": time.perf_counter() - t0})
        return rows, dofs_n

    # Hyperelastic: energy, its derivative, minus the pressure's virtual work.
    wt = ufl.TestFunction(W)
    v = ufl.split(wt)[0] if mixed else wt
    F2 = I2 + ufl.grad(u)
    C2 = F2.T * F2
    J2 = ufl.det(F2)
    if model == "svk":
        E2 = 0.5 * (C2 - I2)
        psi = 0.5 * lam2 * ufl.tr(E2) ** 2 + mu * ufl.inner(E2, E2)
        lam3 = ufl.sqrt(1.0 - 2.0 * lam / (lam + 2.0 * mu) * ufl.tr(E2)) if state == "stress" else 1.0
    else:
        lam3 = (1.0 + ufl.split(w)[1]) if mixed else 1.0
        J = J2 * lam3
        psi = 0.5 * mu * (ufl.tr(C2) + lam3**2 - 3.0) - mu * ufl.ln(J) + 0.5 * lam * ufl.ln(J) ** 2
    Fres = ufl.derivative(psi * dx, w, wt)
    if load == "follower":
        y = X[1] + u[1]
        trac = p_at(y) * lam3 * J2 * ufl.dot(ufl.inv(F2).T, ex)  # -p J F^-T N, N = -e_x
    else:
        trac = p_at(X[1]) * ex
    Fres = Fres - ufl.dot(trac, v) * ds(1)
    problem = NonlinearProblem(Fres, w, bcs=[bc])
    solver = NewtonSolver(MPI.COMM_WORLD, problem)
    solver.convergence_criterion = "incremental"
    solver.rtol = 1e-10
    solver.atol = 1e-13
    solver.max_it = 25
    solver.error_on_nonconvergence = False
    ksp = solver.krylov_solver
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")

    path = sorted(set([h for h in RAMP if h < levels[0]] + list(levels)))
    want = set(levels)
    h_done = 0.0
    w_done = w.x.array.copy()
    its_acc, t_acc = 0, 0.0
    for target in path:
        step = target - h_done
        while h_done < target - 1e-12:
            h_try = min(target, h_done + step)
            H.value = h_try
            t0c = time.perf_counter()
            try:
                n, ok = solver.solve(w)
            except RuntimeError:
                n, ok = solver.max_it, False
            t_acc += time.perf_counter() - t0c
            its_acc += int(n)
            if ok and np.all(np.isfinite(w.x.array)):
                h_done, w_done = h_try, w.x.array.copy()
            else:
                w.x.array[:] = w_done
                w.x.scatter_forward()
                step *= 0.5
                log(f"      {state} {model} {load}: Newton failed at H = {h_try:.5f}, step -> {step:.2e}")
                if step < 1e-5:
                    sys.exit(f"{state} {model} {load}: no convergence at H = {h_try}")
        if any(abs(target - h) < 1e-12 for h in want):
            rows.append({"H": target, "tip": tip(), "its": its_acc, "s": t_acc})
            its_acc, t_acc = 0, 0.0
    return rows, dofs_n


def level_for_tip(hs, tips, target):
    """Level at which the tip reaches target: the root of a cubic through the four stored
    levels around it (tip(H) is smooth and increasing); None when target lies outside the
    stored tips."""
    hs, tips = np.asarray(hs, dtype=float), np.asarray(tips, dtype=float)
    if not (tips.min() <= target <= tips.max()):
        return None
    k = int(np.clip(np.searchsorted(tips, target), 1, len(hs) - 1))  # tips[k-1] <= target <= tips[k]
    sl = slice(max(k - 2, 0), min(k + 2, len(hs)))
    c = np.polyfit(hs[sl], tips[sl], min(3, len(hs[sl]) - 1))
    lo, hi = hs[k - 1], hs[k]
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if np.polyval(c, mid) < target:
            lo = mid
        else:
            hi = mid
    return float(0.5 * (lo + hi))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--meshes", nargs="+", default=DEFAULT_MESHES, help="NXxNY cells (default %(default)s)")
    ap.add_argument("--levels", nargs="+", type=float, default=DEFAULT_LEVELS, help="water levels H (m)")
    ap.add_argument("--states", nargs="+", default=STATES, choices=STATES)
    ap.add_argument("--models", nargs="+", default=[f"{m}-{l}" for m, l in MODELS],
                    choices=[f"{m}-{l}" for m, l in MODELS])
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args()
    from mpi4py import MPI
    import dolfinx
    from petsc4py import PETSc

    if MPI.COMM_WORLD.size != 1:
        sys.exit("gate_static.py is serial: run it without mpirun")
    levels = sorted(args.levels)
    models = [tuple(m.split("-")) for m in args.models]
    t_all = time.perf_counter()

    def log(msg):
        print(msg, flush=True)

    rows, timings = [], {}
    t0 = time.perf_counter()
    beam = {}
    for state in args.states:
        for load in ("follower", "dead"):
            face = elastica_tips(levels, state, load, face=True)
            axis = elastica_tips(levels, state, load, face=False)
            beam[(state, load)] = {h: (f[0], f[1], a[0]) for h, f, a in zip(levels, face, axis)}
    timings["elastica"] = time.perf_counter() - t0
    for mname in args.meshes:
        nx, ny = parse_mesh(mname)
        gate = Gate(nx, ny)
        for state in args.states:
            for model, load in models:
                t0 = time.perf_counter()
                res, dofs = solve_case(gate, state, model, load, levels, log)
                timings[f"{mname}/{state}/{model}/{load}"] = time.perf_counter() - t0
                for r in res:
                    eb, tim = beam_tips(r["H"], state)
                    el = beam[(state, load)][r["H"]] if model != "linear" else (float("nan"),) * 3
                    rows.append({"mesh": mname, "nx": nx, "ny": ny, "dofs": dofs, "state": state, "model": model,
                                 "load": load, "H": r["H"], "tip_x": r["tip"][0], "tip_y": r["tip"][1],
                                 "beam_eb": eb, "beam_timoshenko": tim, "elastica_x": el[0], "elastica_y": el[1],
                                 "elastica_axis_x": el[2], "newton_its": r["its"], "solve_s": r["s"]})
                at = {r["H"]: r["tip"] for r in res}
                h14 = min(at, key=lambda h: abs(h - 0.140))
                log(f"{mname} {state:6s} {model:6s} {load:8s}: tip at H = {h14:.3f}: {1e3 * at[h14][0]:7.3f} / "
                    f"{1e3 * at[h14][1]:6.3f} mm, {timings[f'{mname}/{state}/{model}/{load}']:.1f} s")

    def case(mesh, state, model, load):
        """The rows of one case, by level."""
        return sorted((r for r in rows if (r["mesh"], r["state"], r["model"], r["load"]) == (mesh, state, model, load)),
                      key=lambda r: r["H"])

    # Mesh convergence: the largest relative change of the horizontal tip between the two finest meshes.
    conv = {}
    if len(args.meshes) >= 2:
        for state in args.states:
            for model, load in models:
                c = case(args.meshes[-2], state, model, load)
                f = case(args.meshes[-1], state, model, load)
                conv[f"{state}/{model}/{load}"] = max(abs(b["tip_x"] - a["tip_x"]) / abs(b["tip_x"]) for a, b in zip(c, f))
    finest = args.meshes[-1]
    need, need_t, beam_check = {}, {}, {}
    for state in args.states:
        for model, load in models:
            key = f"{state}/{model}/{load}"
            sel = case(finest, state, model, load)
            hs, tx = [r["H"] for r in sel], [r["tip_x"] for r in sel]
            need[key] = level_for_tip(hs, tx, EXP_PEAK_TIP)
            need_t[key] = [level_for_tip(hs, tx, d) for d in EXP_X]
            if model == "linear":
                q = [r["tip_x"] / r["beam_eb"] for r in sel]
                qt = [r["tip_x"] / r["beam_timoshenko"] for r in sel]
                beam_check[key] = {"tip_x_over_euler_bernoulli": [min(q), max(q)],
                                   "tip_x_over_timoshenko": [min(qt), max(qt)]}
            else:
                qx = [r["tip_x"] / r["elastica_x"] for r in sel]
                qy = [r["tip_y"] / r["elastica_y"] for r in sel]
                beam_check[key] = {"tip_x_over_elastica": [min(qx), max(qx)], "tip_y_over_elastica": [min(qy), max(qy)]}
    script = Path(__file__).resolve()
    lam, mu = lame(E_RUBBER, NU_RUBBER)
    doc = {
        "description": "Elastic gate (Antoci et al. 2007) under still water of level H, static, 2-D, FEniCSx P2 "
                       "triangles: mean horizontal (downstream) and vertical (up) displacement of the free tip "
                       "edge y = Y0, per mesh, state (plane stress/strain), model (linear, St. Venant-Kirchhoff, "
                       "compressible neo-Hookean) and load (follower: pressure of the deformed height on the deformed "
                       "face; dead: pressure of the reference height on the reference face, along x).",
        "provenance": {
            "tool": "FEniCSx (Debian python3-dolfinx)",
            "versions": {"dolfinx": dolfinx.__version__, "petsc": ".".join(map(str, PETSc.Sys.getVersion())),
                         "python": platform.python_version()},
            "script": "references/fenicsx/" + script.name, "script_sha256": sha256_file(script),
            "solver": "PETSc KSP preonly + LU (MUMPS); Newton (dolfinx.nls.petsc.NewtonSolver, incremental "
                      "criterion, rtol 1e-10), load-stepped in H",
            "meshes": {m: f"dolfinx.mesh.create_rectangle [0, {T_GATE}] x [{Y0}, {Y0 + L_GATE}], {parse_mesh(m)[0]} x "
                          f"{parse_mesh(m)[1]} cells, 2 triangles each (diagonal 'right'), Lagrange P2"
                       for m in args.meshes},
            "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
            "machine": machine.describe(), "threads": 1,
            "wall_s": time.perf_counter() - t_all, "case_wall_s": timings,
        },
        "problem": {"T": T_GATE, "L": L_GATE, "Y0": Y0, "E": E_RUBBER, "nu": NU_RUBBER, "lambda": lam, "mu": mu,
                    "lambda_plane_stress": 2 * mu * lam / (lam + 2 * mu), "rho_w": RHO_W, "g": G,
                    "clamp": "u = 0 on y = Y0 + L", "load": "p = rho_w g max(H - y, 0) on x = 0 (upstream)",
                    "tip": "mean of u over the edge y = Y0 (reference), m", "levels": levels},
        "mesh_convergence": {"meshes": args.meshes[-2:], "max_rel_change_tip_x": conv},
        "beam_check": {"mesh": finest, "ranges_over_levels": beam_check,
                       "note": "linear rows against the linear beam; nonlinear rows against the face-loaded elastica"},
        "level_for_experiment_peak": {"tip": EXP_PEAK_TIP, "mesh": finest, "levels_m": need,
                                      "note": "None: the tip does not reach it within the levels computed"},
        "level_for_experiment_tips": {"t": EXP_T, "tip": EXP_X, "mesh": finest, "levels_m": need_t,
                                      "note": "the still-water level whose static tip equals the experiment's "
                                              "horizontal tip at each tabulated time; None: outside the levels"},
        "rows": "gate_static.csv",
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "gate_static.json").write_text(json.dumps(doc, indent=1) + "\n")
    with open(out / "gate_static.csv", "w") as f:
        p = doc["provenance"]
        f.write(f"# source: FEniCSx dolfinx {p['versions']['dolfinx']} ({p['script']}), {p['date']}, "
                f"{p['machine']['cpu']}, 1 thread; gate {T_GATE} x {L_GATE} m, E {E_RUBBER:g} Pa, nu {NU_RUBBER}, "
                f"still water of level H on x < 0; tip = mean over the free edge (m); provenance in gate_static.json\n")
        f.write(",".join(FIELDS) + "\n")
        for r in rows:
            f.write(",".join(f"{r[k]:.10g}" if isinstance(r[k], float) else str(r[k]) for k in FIELDS) + "\n")
    log(f"mesh convergence (max rel. change of tip_x, {' -> '.join(args.meshes[-2:])}): "
        + ", ".join(f"{k} {v:.2e}" for k, v in conv.items()))
    log("level for the experiment's 46.4 mm: " + ", ".join(
        f"{k} {'none' if v is None else f'{v:.4f} m'}" for k, v in need.items()))
    log(f"wrote {out}/gate_static.csv|json in {time.perf_counter() - t_all:.1f} s")


if __name__ == "__main__":
    main()
