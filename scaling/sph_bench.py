#!/usr/bin/env python3
"""SPH throughput benchmark: particle-steps per second of the full SPH step (sort, density,
wall pressure, forces, integration: the "sph" phase timer of `qdemsph run`) for a dam-break
block in a tank, at given particle counts, on one backend. Writes a JSON record.

  /usr/bin/python3 scaling/sph_bench.py --backend cpu  --particles 2e4,1e5 --steps 50 --json OUT.json
  /usr/bin/python3 scaling/sph_bench.py --backend cuda --particles 1e6,1e7 --steps 200 --json OUT.json

The particle count is fluid + wall particles (every particle is sorted and updated each step;
wall particles also get the Adami pressure). Bytes per particle: the stage's buffers
(summary.json fluid.device_bytes / particles)."""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import re
import subprocess
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

SCENE = """name: sph_bench
run: {{end_time: {end}, backend: {backend}}}
gravity: [0, -9.81, 0]
fluid:
  spacing: {dx}
  blocks: [{{min: [0, 0, 0], max: [1.0, 0.5, {w}]}}]
  tanks: [{{min: [0, 0, 0], max: [2.0, 0.6, {w}], thickness_layers: 3}}]
output: {{fields_every: 0, probes_every: {end}}}
"""


def machine():
    cpu = platform.processor()
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    gpu = ""
    try:
        gpu = subprocess.run(["nvidia-smi", "--query-gpu=name", "--format=csv,noheader"],
                             capture_output=True, text=True, timeout=20).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return {"host": platform.node(), "cpu": cpu, "cores": os.cpu_count(), "gpu": gpu,
            "omp_num_threads": os.environ.get("OMP_NUM_THREADS", "")}


def particles_for(dx, w):
    # fluid block + tank walls (3 layers, open top), as build_fluid places them
    n = [round(1.0 / dx), round(0.5 / dx), round(w / dx)]
    t = [round(2.0 / dx), round(0.6 / dx), round(w / dx)]
    tank = (t[0] + 6) * (t[1] + 3) * (t[2] + 6) - t[0] * t[1] * t[2]
    return n[0] * n[1] * n[2] + tank


def dx_for(target, w_ratio=0.25):
    # bisection on dx for the requested total particle count (slab depth w = w_ratio m)
    lo, hi = 1e-4, 0.2
    for _ in range(60):
        mid = (lo * hi) ** 0.5
        if particles_for(mid, w_ratio) > target:
            lo = mid
        else:
            hi = mid
    return hi


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--particles", default="2e4", help="comma-separated total particle counts")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--qdemsph", default=os.environ.get("QDEMSPH", str(REPO / "build" / "bin" / "qdemsph")))
    ap.add_argument("--json", default=None, help="output record (default: print only)")
    ap.add_argument("--wrap", default="", help="a command the solver run is started under, e.g. a "
                    "profiler (ci/gpu_session.sh SPH_PROFILE=1 uses ncu)")
    a = ap.parse_args()
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for target in [float(x) for x in a.particles.split(",")]:
            dx = dx_for(target)
            scene = Path(tmp) / "scene.yaml"
            scene.write_text(SCENE.format(end=1.0, backend=a.backend, dx=f"{dx:.6g}", w=0.25))
            info = subprocess.run([a.qdemsph, "info", str(scene)], capture_output=True, text=True, check=True).stdout
            dtf = float(re.search(r"fluid dt\s+([0-9.eE+-]+)", info).group(1))
            end = a.steps * dtf * (1 - 1e-9)
            scene.write_text(SCENE.format(end=f"{end:.9g}", backend=a.backend, dx=f"{dx:.6g}", w=0.25))
            out = Path(tmp) / f"out_{int(target)}"
            subprocess.run(a.wrap.split() + [a.qdemsph, "run", str(scene), "--out", str(out), "--quiet"],
                           check=True)
            s = json.loads((out / "summary.json").read_text())
            f = s["fluid"]
            n = f["n_fluid"] + f["n_wall"]
            rec = {"particles": n, "fluid": f["n_fluid"], "wall": f["n_wall"], "dx": dx, "steps": s["steps"],
                   "backend": s["backend"], "threads": s.get("threads"), "sph_s": s["phases"].get("sph"),
                   "wall_s": s["wall_s"], "particle_steps_per_s": f["particle_steps_per_s"],
                   "bytes_per_particle": f["device_bytes"] / n}
            print(json.dumps(rec))
            runs.append(rec)
    record = {"benchmark": "sph_step", "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
              "machine": machine(), "runs": runs,
              "note": "particle-steps/s of the 'sph' phase (sort + density + Adami + forces + kicks/drift), "
                      "fluid + wall particles, double precision, Wendland C2 h = 1.3 dx"}
    if a.json:
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
