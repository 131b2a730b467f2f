#!/usr/bin/env python3
"""The long-tier 27-cube stack (verification/cases/contact_stack/scene_27.yaml, the report's
cubes of 6,144 tets, 1 s) as one record: the case's settling metrics (stack_metrics.py: kinetic
energy decay, lateral drift over the last 0.5 s against D_DEM, largest overlap against
2 D_DEM), wall time, time per step of each phase, and the energy series.

  ci/gpu/stack_run.py RUN_DIR OUT.json     (RUN_DIR: a finished `qdemsph run` output folder)
Prints one line "STACK27 {...}" for the session table."""
import csv
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "verification/cases/contact_stack"))
from stack_metrics import D_DEM, stack_metrics  # noqa: E402


def main():
    run, out = Path(sys.argv[1]), Path(sys.argv[2])
    s = json.loads((run / "summary.json").read_text())
    rows = list(csv.DictReader(open(run / "probes.csv")))
    p = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    m = stack_metrics(p, s, 0.5)
    steps = max(s.get("steps", 1), 1)
    rec = {"scene": s.get("scene"), "status": s.get("status"),
           "backend": s.get("backend"), "sim_time": s.get("sim_time"), "steps": s.get("steps"),
           "dt": s.get("dt"), "wall_s": s.get("wall_s"), "n_tets": s.get("n_tets"), "d_dem": D_DEM,
           "metrics": m,
           "pass": {"ke_end_over_peak < 0.5": m["ke_end_over_peak"] < 0.5,
                    "lateral_drift < D_DEM": m["lateral_drift"] < D_DEM,
                    "max_overlap < 2 D_DEM": m["max_overlap"] < 2 * D_DEM},
           "seconds_per_step": {k: v / steps for k, v in s.get("phases", {}).items()},
           "contact": s.get("contact"), "energies_end": s.get("energies"),
           "series": {k: p[k].tolist() for k in ("time", "kinetic", "strain", "potential", "dissipated",
                                                 "contact", "contact_dissipated", "total") if k in p}}
    out.write_text(json.dumps(rec, indent=1) + "\n")
    print("STACK27 " + json.dumps({k: rec[k] for k in ("status", "backend", "sim_time", "steps", "wall_s",
                                                       "metrics", "pass")}), flush=True)


if __name__ == "__main__":
    main()
