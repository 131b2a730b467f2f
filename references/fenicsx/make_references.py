#!/usr/bin/python3
"""Regenerate the stored FEniCSx cantilever references (called by make_references.sh,
i.e. `make references`).

For each beam of the ladder (default 10x1x1, 20x2x2, 40x4x4, 80x8x8 with P1 and P2, and
150x15x15 = 405,000 tets with P1 only):
  1. write the scene verification/cases/cantilever_convergence/scene.yaml with `cells` set,
  2. export its mesh with `qdemsph mesh` (the identical mesh qdemsph solves on),
  3. solve with cantilever.py (P1, P2), one after the other (serial, one thread each).
Then write results/tip_deflection.{csv,json} (every run with mesh hashes, dofs, times and the
machine) and results/provenance/<mesh>.json, and the converged reference: Richardson
extrapolation of the three finest P2 tip deflections with their observed rate.

--own-meshes builds the 12-tet box meshes in Python instead of asking qdemsph (for testing the
scripts before the solver exists; such results are marked and the verification rejects them
when their mesh hash differs from qdemsph's export).
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(REPO / "verification"))
import meshio41  # noqa: E402
from harness import machine  # noqa: E402
from harness.qdemsph import Qdemsph, write_scene_variant  # noqa: E402

TEMPLATE = REPO / "verification" / "cases" / "cantilever_convergence" / "scene.yaml"
DEFAULT_LEVELS = ["10x1x1", "20x2x2", "40x4x4", "80x8x8", "150x15x15"]
FIELDS = ["mesh", "degree", "n_vertices", "n_tets", "dofs", "tip_deflection", "ratio_eb",
          "ratio_timoshenko", "solve_s", "total_s", "mesh_source", "mesh_sha256", "mesh_content_sha256"]


def parse_cells(name):
    cells = [int(c) for c in name.lower().split("x")]
    if len(cells) != 3 or min(cells) < 1:
        raise argparse.ArgumentTypeError(f"mesh level must look like 20x2x2, got {name!r}")
    return cells


def export_mesh(level, work, qdemsph, own):
    cells = parse_cells(level)
    mdir = work / "meshes" / level
    if mdir.exists():
        shutil.rmtree(mdir)
    mdir.mkdir(parents=True)
    if own:
        pts, tets = meshio41.box_mesh([1.0, 0.1, 0.1], cells)
        path = mdir / "beam.msh"
        meshio41.write_msh41(path, pts, tets)
        return path, "meshio41.box_mesh (NOT qdemsph: testing only)"
    scene = write_scene_variant(TEMPLATE, work / "scenes" / f"beam_{level}.yaml",
                                cells=f"[{cells[0]}, {cells[1]}, {cells[2]}]")
    meshes = qdemsph.mesh(scene, mdir)
    if "beam" not in meshes:
        sys.exit(f"qdemsph mesh wrote {sorted(meshes)}, expected beam.msh")
    return meshes["beam"], f"qdemsph mesh ({qdemsph.binary.relative_to(REPO) if qdemsph.binary.is_relative_to(REPO) else qdemsph.binary})"


def solve(mesh, degree, out):
    cmd = [sys.executable, str(HERE / "cantilever.py"), "--mesh", str(mesh), "--degree", str(degree),
           "--out", str(out)]
    print("  $", " ".join(cmd), flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"cantilever.py failed ({proc.returncode}):\n{proc.stderr[-3000:]}")
    print("   ", proc.stdout.strip().splitlines()[-1], flush=True)
    return json.loads((out / f"result_p{degree}.json").read_text()), json.loads((out / "provenance.json").read_text())


def converged_reference(rows):
    """Richardson extrapolation from the three finest P2 meshes (refinement ratio 2)."""
    p2 = sorted((r for r in rows if r["degree"] == 2), key=lambda r: r["n_tets"])
    if len(p2) < 3:
        last = p2[-1]
        return {"value": last["tip_deflection"], "method": f"P2 on {last['mesh']} (fewer than 3 P2 meshes: "
                "no extrapolation)", "uncertainty": None, "observed_rate": None, "from": [last["mesh"]]}
    a, b, c = (r["tip_deflection"] for r in p2[-3:])
    ratios = [parse_cells(p2[-2]["mesh"])[0] / parse_cells(p2[-3]["mesh"])[0],
              parse_cells(p2[-1]["mesh"])[0] / parse_cells(p2[-2]["mesh"])[0]]
    if any(abs(q - 2.0) > 1e-12 for q in ratios):
        sys.exit(f"Richardson needs refinement ratio 2 between the three finest P2 meshes, got {ratios}")
    rate = math.log(abs((b - a) / (c - b))) / math.log(2.0)
    extrap = c + (c - b) / (2.0**rate - 1.0)
    return {"value": extrap, "method": "Richardson extrapolation of the three finest P2 tip deflections "
            "with their observed rate", "observed_rate": rate, "finest_p2": c,
            "uncertainty": abs(extrap - c), "uncertainty_rel": abs(extrap - c) / abs(extrap),
            "from": [r["mesh"] for r in p2[-3:]]}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--levels", nargs="+", default=DEFAULT_LEVELS, help="meshes NXxNYxNZ (default: %(default)s)")
    ap.add_argument("--p2-max-tets", type=int, default=70000, help="P2 only on meshes up to this many tets")
    ap.add_argument("--qdemsph", default=os.environ.get("QDEMSPH", str(REPO / "build" / "bin" / "qdemsph")))
    ap.add_argument("--own-meshes", action="store_true", help="build meshes in Python (testing only)")
    ap.add_argument("--work", default=str(REPO / "build" / "references"), help="scratch folder")
    ap.add_argument("--results", default=str(HERE / "results"), help="where the stored references go")
    args = ap.parse_args()
    for lv in args.levels:
        parse_cells(lv)
    work, results = Path(args.work), Path(args.results)
    qd = Qdemsph(args.qdemsph)
    if not args.own_meshes:
        qd.check()
    rows, provs = [], {}
    for level in args.levels:
        mesh, source = export_mesh(level, work, qd, args.own_meshes)
        pts, tets, _ = meshio41.read_msh41(mesh)
        chash = meshio41.content_hash(pts, tets)
        print(f"{level}: {len(pts)} vertices, {len(tets)} tets ({source})", flush=True)
        degrees = [1] + ([2] if len(tets) <= args.p2_max_tets else [])
        for d in degrees:
            res, prov = solve(mesh, d, work / "fenicsx" / level)
            rows.append({"mesh": level, "degree": d, "n_vertices": res["n_vertices"], "n_tets": res["n_tets"],
                         "dofs": res["dofs"], "tip_deflection": res["tip_deflection"], "ratio_eb": res["ratio_eb"],
                         "ratio_timoshenko": res["ratio_timoshenko"], "solve_s": res["solve_s"],
                         "total_s": res["total_s"], "mesh_source": source, "mesh_sha256": prov["mesh_sha256"],
                         "mesh_content_sha256": chash, "d_euler_bernoulli": res["d_euler_bernoulli"],
                         "d_timoshenko": res["d_timoshenko"]})
        prov["mesh"] = f"{level} beam exported by {source}"
        prov["mesh_content_sha256"] = chash
        provs[level] = prov
    conv = converged_reference(rows)
    first = next(iter(provs.values()))
    doc = {
        "description": "Cantilever tip deflection (integral mean of uz over the x = L face), FEniCSx "
                       "P1/P2 on the meshes qdemsph exports; E = 1e7, nu = 0.3, L = 1, b = h = 0.1, "
                       "traction -100 Pa (P = 1 N) on x = L, x = 0 clamped.",
        "provenance": {"tool": first["tool"], "versions": first["versions"], "script": first["script"],
                       "script_sha256": first["script_sha256"], "driver": "references/fenicsx/make_references.py",
                       "solver": first["solver"],
                       "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
                       "machine": machine.describe(), "threads": 1,
                       "own_meshes": bool(args.own_meshes)},
        "d_euler_bernoulli": rows[0]["d_euler_bernoulli"], "d_timoshenko": rows[0]["d_timoshenko"],
        "converged": conv, "rows": rows,
    }
    results.mkdir(parents=True, exist_ok=True)
    (results / "provenance").mkdir(exist_ok=True)
    (results / "tip_deflection.json").write_text(json.dumps(doc, indent=1) + "\n")
    with open(results / "tip_deflection.csv", "w") as f:
        p = doc["provenance"]
        f.write(f"# source: FEniCSx dolfinx {p['versions']['dolfinx']} ({p['script']} via {p['driver']}), "
                f"{p['date']}, {p['machine']['cpu']}, 1 thread; converged P2 reference "
                f"{conv['value']:.10e} ({conv['method']})\n")
        f.write(",".join(FIELDS) + "\n")
        for r in rows:
            f.write(",".join(f"{r[k]:.12g}" if isinstance(r[k], float) else str(r[k]) for k in FIELDS) + "\n")
    for level, prov in provs.items():
        (results / "provenance" / f"{level}.json").write_text(json.dumps(prov, indent=1) + "\n")
    print(f"converged reference {conv['value']:.8e} (rate {conv.get('observed_rate')}); "
          f"wrote {results}/tip_deflection.csv|json", flush=True)


if __name__ == "__main__":
    main()
