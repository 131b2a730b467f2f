#!/usr/bin/env python3
"""The cantilever refinement ladder on one backend: `qdemsph run` (linear law, static) of
verification/cases/cantilever_convergence/scene.yaml for each mesh, tip deflection as the
integral mean of w over the tip face (as FEniCSx reports it), error against the converged
P2 reference, wall time. Writes one JSON record: the GPU series of the speed-against-error
chart (the CPU and FEniCSx series come from make verify).

  python3 ci/gpu/cantilever_ladder.py QDEMSPH BACKEND OUT.json [10x1x1 20x2x2 ...]
Needs numpy and h5py."""
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "references" / "fenicsx"))
import meshio41  # noqa: E402

SCENE = REPO / "verification/cases/cantilever_convergence/scene.yaml"
REF = json.loads((REPO / "references/fenicsx/results/tip_deflection.json").read_text())["converged"]


def main():
    qdemsph, backend, out = sys.argv[1:4]
    meshes = sys.argv[4:] or ["10x1x1", "20x2x2", "40x4x4", "80x8x8", "150x15x15"]
    records = []
    for m in meshes:
        cells = m.replace("x", ",")
        with tempfile.TemporaryDirectory() as d:
            t0 = time.time()
            p = subprocess.run([qdemsph, "run", str(SCENE), "-q", "-b", backend, "-o", d,
                                "--set", f"bodies.0.mesh.cells=[{cells}]"],
                               capture_output=True, text=True)
            wall = time.time() - t0
            summ = json.loads((Path(d) / "summary.json").read_text())
            with h5py.File(Path(d) / "fields.h5", "r") as f:
                pts = f["mesh/points"][...]
                tets = f["mesh/tets"][...]
                last = sorted(f["steps"].keys())[-1]
                disp = f["steps"][last]["displacement"][...]
        w, _ = meshio41.face_mean(pts, tets, disp[:, 2], axis=0, coord=1.0, tol=1e-9)
        rec = {"mesh": m, "tets": int(len(tets)), "backend": summ["backend"], "rc": p.returncode,
               "status": summ["status"], "static": summ.get("static"), "wall_s": wall,
               "solver_wall_s": summ["wall_s"], "tip_deflection": float(w),
               "error_vs_converged": abs(w / REF["value"] - 1.0)}
        records.append(rec)
        print(f"{m:>10} {rec['tets']:>8} tets  tip {w:.6e}  err {rec['error_vs_converged']:.4f}  "
              f"{summ['static']['iterations']} it  {summ['wall_s']:.2f} s  {summ['status']}", flush=True)
    Path(out).write_text(json.dumps({"case": "cantilever_convergence", "backend": backend,
                                     "converged_reference": REF, "records": records}, indent=1))


if __name__ == "__main__":
    main()
