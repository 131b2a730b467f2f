#!/usr/bin/env python3
"""Compare two qdemsph output folders (CPU and CUDA runs of one scene).

usage: compare_runs.py NAME CPU_DIR CUDA_DIR  -> prints one JSON object on stdout.
Differences are max |a - b| / max |b| over vertices (displacement = position - reference,
velocity) or tets (von Mises) of the last field frame; energies relative to the sum of the
magnitudes of the energy terms; probes over every row (probes.csv keeps 11 digits, so
1e-10 is its floor). Needs h5py for the fields (present on the GPU machines).
"""
import csv, json, sys


def rel(a, b):
    import numpy as np
    a, b = np.asarray(a, float), np.asarray(b, float)
    s = float(np.abs(b).max()) if b.size else 0.0
    d = float(np.abs(a - b).max()) if b.size else 0.0
    return d / s if s > 0 else d


def last_frame(path):
    import h5py
    f = h5py.File(path, "r")
    k = sorted(f["steps"].keys())[-1]
    g = f["steps"][k]
    return {n: g[n][()] for n in ("displacement", "velocity", "von_mises") if n in g}


def main():
    name, cdir, gdir = sys.argv[1:4]
    out = {"scene": name}
    sc = json.load(open(f"{cdir}/summary.json"))
    sg = json.load(open(f"{gdir}/summary.json"))
    out["status"] = [sc.get("status"), sg.get("status")]
    out["steps"] = [sc.get("steps"), sg.get("steps")]
    for key in ("static", "preload"):
        if key in sc:
            out[key + "_iterations"] = [sc[key]["iterations"], sg.get(key, {}).get("iterations")]
    ec, eg = sc["energies"], sg["energies"]
    scale = sum(abs(ec[k]) for k in ("kinetic", "strain", "potential", "dissipated")) or 1.0
    out["energy_max_rel"] = max(abs(eg[k] - ec[k]) / scale for k in ("kinetic", "strain", "potential", "dissipated"))
    out["wall_s"] = [sc.get("wall_s"), sg.get("wall_s")]
    try:
        fc, fg = last_frame(f"{cdir}/fields.h5"), last_frame(f"{gdir}/fields.h5")
        for k in fc:
            out[k + "_max_rel"] = rel(fg[k], fc[k])
    except ImportError:
        out["fields"] = "h5py missing: fields not compared"
    rc = list(csv.reader(open(f"{cdir}/probes.csv")))
    rg = list(csv.reader(open(f"{gdir}/probes.csv")))
    cols = [i for i, h in enumerate(rc[0]) if h not in ("time",) and h not in ("kinetic", "strain", "potential", "dissipated", "total")]
    if len(rc) == len(rg) and cols:
        out["probes_max_rel"] = rel([[float(r[i]) for i in cols] for r in rg[1:]],
                                    [[float(r[i]) for i in cols] for r in rc[1:]])
    else:
        out["probes"] = f"row count differs: cpu {len(rc)} cuda {len(rg)}"
    print(json.dumps(out))


if __name__ == "__main__":
    main()
