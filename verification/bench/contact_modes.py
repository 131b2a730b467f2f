#!/usr/bin/env python3
"""Benchmark record of the report's Fig. 7: time per step of each phase on the 27-cube stack
with (A) all tets in the cell list, (B) surface tets only, (C) surface polygons only
(scene key contact.broad_phase = all_tets | surface_tets | polygons), the pair list rebuilt
every step as in the report (contact.skin = 0).

    /usr/bin/python3 verification/bench/contact_modes.py [--small] [--steps N] [--out FILE]
                                                         [--qdemsph PATH] [--threads T]

Writes a JSON record (default build/bench/contact_modes.json): machine, scene, steps, and per
mode the seconds per step of every phase (elements, integration, contact, contact.broad,
contact.narrow, contact.force), the candidate pairs and contacts of the last step, and the
ratios A/C and B/C of the contact phase and of its broad phase."""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
STACK = REPO / "verification" / "cases" / "contact_stack"
MODES = {"A": "all_tets", "B": "surface_tets", "C": "polygons"}


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def run_mode(binary, scene, mode, steps, dt_fixed, threads, out):
    cmd = [str(binary), "run", str(scene), "--out", str(out), "--quiet",
           "--set", f"contact.broad_phase={mode}", "--set", "contact.skin=0", "--set", f"run.dt={dt_fixed}",
           "--set", f"run.end_time={steps * dt_fixed * (1 - 1e-6)}",
           "--set", f"output.probes_every={steps * dt_fixed}"]
    if threads:
        cmd += ["--set", f"run.threads={threads}"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    s = json.loads((out / "summary.json").read_text())
    n = max(int(s["steps"]), 1)
    return {"broad_phase": mode, "steps": n, "wall_s": s["wall_s"],
            "seconds_per_step": {k: v / n for k, v in s["phases"].items()},
            "contact": s.get("contact", {})}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--small", action="store_true", help="2x2x2 stack of 768-tet cubes instead of the report's 27")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--dt", type=float, default=1.5e-4, help="fixed time step [s] (below both stacks' limits)")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--qdemsph", default=os.environ.get("QDEMSPH", str(REPO / "build" / "bin" / "qdemsph")))
    ap.add_argument("--out", default=str(REPO / "build" / "bench" / "contact_modes.json"))
    a = ap.parse_args()
    scene = STACK / ("scene_8.yaml" if a.small else "scene_27.yaml")
    rec = {"benchmark": "contact_broad_phase_modes (report Fig. 7)",
           "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
           "machine": {"cpu": cpu_model(), "cores": os.cpu_count(), "host": platform.node()},
           "scene": str(scene.relative_to(REPO)), "steps": a.steps, "dt": a.dt, "threads": a.threads,
           "modes": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for key, mode in MODES.items():
            r = run_mode(a.qdemsph, scene, mode, a.steps, a.dt, a.threads, Path(tmp) / mode)
            rec["modes"][key] = r
            sp = r["seconds_per_step"]
            print(f"({key}) {mode:13s} contact {sp.get('contact', 0) * 1e3:9.3f} ms/step "
                  f"(broad {sp.get('contact.broad', 0) * 1e3:8.3f}, narrow {sp.get('contact.narrow', 0) * 1e3:8.3f}, "
                  f"force {sp.get('contact.force', 0) * 1e3:7.3f}), elements {sp.get('elements', 0) * 1e3:8.3f}; "
                  f"{r['contact'].get('primitives')} primitives, {r['contact'].get('pairs')} pairs", file=sys.stderr)
    c = rec["modes"]["C"]["seconds_per_step"]
    rec["ratios"] = {}
    for key in ("A", "B"):
        m = rec["modes"][key]["seconds_per_step"]
        for ph in ("contact", "contact.broad", "contact.narrow"):
            if c.get(ph):
                rec["ratios"][f"{key}/C {ph}"] = m.get(ph, 0) / c[ph]
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rec, indent=2) + "\n")
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
