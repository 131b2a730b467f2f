#!/usr/bin/env python3
"""Contact throughput on many-body scenes: grids of the report's cubes (1 m, 8x8x8 hexes =
6,144 tets, 768 surface triangles each, 1 cm apart, on a floor, under gravity; the 3x3x3 grid
is verification/cases/contact_stack/scene_27.yaml) stepped at a fixed dt with `qdemsph run`.

  ci/gpu/contact_bench.py QDEMSPH --backend cuda --grids 3,6 --steps 200 --json OUT.json

Per run, from summary.json: seconds per step of each phase, the candidate pairs of surface
triangles (broad phase "polygons", Verlet skin) and the feature contacts of the last step, and
  surface pairs / s = candidate triangle pairs x steps / seconds in the contact stage
  contacts / s      = feature contacts (point-face, edge-edge, wall) x steps / contact seconds
  tet-updates / s   = tets x steps / seconds of the whole step (elements + contact + integration).
The first steps include the first pair-list build; the cubes start touching (gap = D_DEM), so
pairs exist from the first step. CPU runs use every core (OMP_NUM_THREADS unset)."""
import argparse
import datetime as dt
import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

HEAD = """name: contact_bench_{n}x{n}x{n}
run: {{end_time: {end}, dt: {dt}}}
gravity: [0, 0, -9.81]
materials:
  block: {{E: 1.0e7, nu: 0.3, density: 1000, viscosity: 2000}}
contact: {{mu: 0.5, restitution: 0.3, d_dem: 0.01}}
walls:
  - {{point: [0, 0, 0], normal: [0, 0, 1], mu: 0.5}}
output: {{fields_every: 0, probes_every: {end}}}
bodies:
"""


def scene(n, steps, dt_):
    s = HEAD.format(n=n, end=f"{steps * dt_ * (1 - 1e-9):.9g}", dt=dt_)
    for k in range(n):
        for j in range(n):
            for i in range(n):
                s += (f"  - {{name: c{i}_{j}_{k}, material: block, mesh: {{type: box, origin: "
                      f"[{1.01 * i:.4f}, {1.01 * j:.4f}, {0.01 + 1.01 * k:.4f}], size: [1.0, 1.0, 1.0], "
                      f"cells: [8, 8, 8]}}}}\n")
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("qdemsph")
    ap.add_argument("--backend", default="cuda")
    ap.add_argument("--grids", default="3", help="comma-separated cubes per axis")
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--dt", type=float, default=1.5e-4)
    ap.add_argument("--json", required=True)
    ap.add_argument("--timeout", type=float, default=300)
    a = ap.parse_args()
    out = Path(a.json)
    rec = json.loads(out.read_text()) if out.exists() else {"benchmark": "contact_throughput", "runs": []}
    rec["date"] = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    rec["host_cores"] = os.cpu_count()
    rec["note"] = ("surface pairs/s = candidate surface-triangle pairs x steps / contact seconds; "
                   "contacts/s = feature contacts x steps / contact seconds; tet-updates/s = tets x "
                   "steps / (elements + contact + integration seconds); fixed dt, report cubes")
    with tempfile.TemporaryDirectory() as tmp:
        for n in [int(x) for x in a.grids.split(",")]:
            path = Path(tmp) / f"grid{n}.yaml"
            path.write_text(scene(n, a.steps, a.dt))
            o = Path(tmp) / f"out{n}"
            cmd = [a.qdemsph, "run", str(path), "-q", "-b", a.backend, "-o", str(o)]
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=a.timeout)
            if r.returncode != 0:
                print(f"contact_bench: {n}^3 cubes on {a.backend} failed (rc {r.returncode}): {r.stderr[-2000:]}",
                      file=sys.stderr)
                rec["runs"].append({"backend": a.backend, "cubes": n ** 3, "failed": r.returncode,
                                    "stderr": r.stderr[-2000:]})
                continue
            s = json.loads((o / "summary.json").read_text())
            ph, c, steps = s["phases"], s["contact"], s["steps"]
            contact_s = ph.get("contact", 0.0)
            step_s = ph.get("elements", 0.0) + contact_s + ph.get("integration", 0.0)
            tets = s["n_tets"]
            run = {"backend": s.get("backend", a.backend), "threads": s.get("threads"), "cubes": n ** 3,
                   "tets": tets, "surface_triangles": c.get("surface_triangles"), "steps": steps, "dt": a.dt,
                   "wall_s": s.get("wall_s"),
                   "seconds_per_step": {k: v / steps for k, v in ph.items()},
                   "candidate_pairs": c.get("pairs"), "contacts": c.get("contacts"), "active": c.get("active"),
                   "pair_rebuilds": c.get("pair_rebuilds"), "max_overlap_ever": c.get("max_overlap_ever"),
                   "surface_pairs_per_s": c.get("pairs", 0) * steps / contact_s if contact_s > 0 else None,
                   "contacts_per_s": c.get("contacts", 0) * steps / contact_s if contact_s > 0 else None,
                   "tet_updates_per_s": tets * steps / step_s if step_s > 0 else None,
                   "step_s": step_s / steps if steps else None}
            print("CONTACT_BENCH " + json.dumps({k: run[k] for k in (
                "backend", "cubes", "tets", "steps", "candidate_pairs", "contacts", "surface_pairs_per_s",
                "contacts_per_s", "tet_updates_per_s", "step_s")}), flush=True)
            rec["runs"].append(run)
            out.write_text(json.dumps(rec, indent=1) + "\n")
    out.write_text(json.dumps(rec, indent=1) + "\n")


if __name__ == "__main__":
    main()
