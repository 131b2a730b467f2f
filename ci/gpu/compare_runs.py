#!/usr/bin/env python3
"""Compare two qdemsph output folders (CPU and CUDA runs of one scene).

usage: compare_runs.py NAME CPU_DIR CUDA_DIR  -> prints one JSON object on stdout.
Differences are max |a - b| / max |b| over vertices (displacement = position - reference,
velocity) or tets (von Mises) of the last field frame; energies relative to the sum of the
magnitudes of the energy terms (contact ones included); probes over every row (probes.csv
keeps 11 digits, so 1e-10 is its floor); for a fluid, fluid.csv's columns over every row,
each relative to its largest magnitude; contact counts of the last step must be equal. Needs
h5py for the fields (present on the GPU machines).
"""
import csv, json, os, sys

ENERGIES = ["kinetic", "strain", "potential", "dissipated", "contact", "contact_dissipated"]


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
    missing = [d for d in (cdir, gdir) if not os.path.exists(f"{d}/summary.json")]
    if missing:
        out["status"] = "no summary.json in " + ", ".join(missing) + " (the run failed)"
        print(json.dumps(out))
        return
    sc = json.load(open(f"{cdir}/summary.json"))
    sg = json.load(open(f"{gdir}/summary.json"))
    out["status"] = [sc.get("status"), sg.get("status")]
    out["steps"] = [sc.get("steps"), sg.get("steps")]
    for key in ("static", "preload"):
        if key in sc:
            out[key + "_iterations"] = [sc[key]["iterations"], sg.get(key, {}).get("iterations")]
    ec, eg = sc["energies"], sg["energies"]
    terms = [k for k in ENERGIES if k in ec]
    scale = sum(abs(ec[k]) for k in terms) or 1.0
    out["energy_max_rel"] = max(abs(eg[k] - ec[k]) / scale for k in terms)
    if "contact" in sc:
        out["contact_counts"] = {k: [sc["contact"].get(k), sg.get("contact", {}).get(k)]
                                 for k in ("pairs", "contacts", "active")}
    out["wall_s"] = [sc.get("wall_s"), sg.get("wall_s")]
    try:
        fc, fg = last_frame(f"{cdir}/fields.h5"), last_frame(f"{gdir}/fields.h5")
        for k in fc:
            out[k + "_max_rel"] = rel(fg[k], fc[k])
    except ImportError:
        out["fields"] = "h5py missing: fields not compared"
    except (OSError, KeyError, IndexError) as e:
        out["fields"] = f"no solid fields compared ({type(e).__name__})"
    if os.path.exists(f"{cdir}/fluid.csv"):
        fcv = list(csv.reader(open(f"{cdir}/fluid.csv")))
        fgv = list(csv.reader(open(f"{gdir}/fluid.csv")))
        if len(fcv) == len(fgv):
            col = {h: i for i, h in enumerate(fcv[0])}
            # Momentum components share one scale (a component that is round-off noise in a
            # symmetric flow must not count as a relative difference of 1).
            groups = {"kinetic": ["kinetic"], "momentum": ["px", "py", "pz"], "v_max": ["v_max"],
                      "rho_dev": ["rho_dev"], "front": ["x_max", "y_max"]}
            diffs = {}
            for g, cols_ in groups.items():
                if all(c in col for c in cols_):
                    diffs[g] = rel([[float(r[col[c]]) for c in cols_] for r in fgv[1:]],
                                   [[float(r[col[c]]) for c in cols_] for r in fcv[1:]])
            out["fluid_csv_max_rel"] = max(diffs.values()) if diffs else None
            out["fluid_csv"] = diffs
        else:
            out["fluid"] = f"fluid.csv row count differs: cpu {len(fcv)} cuda {len(fgv)}"
    rc = list(csv.reader(open(f"{cdir}/probes.csv")))
    rg = list(csv.reader(open(f"{gdir}/probes.csv")))
    cols = [i for i, h in enumerate(rc[0]) if h != "time" and h not in ENERGIES + ["total"]]
    if not cols:
        pass  # no probes besides the energies
    elif len(rc) == len(rg):
        out["probes_max_rel"] = rel([[float(r[i]) for i in cols] for r in rg[1:]],
                                    [[float(r[i]) for i in cols] for r in rc[1:]])
    else:
        out["probes"] = f"row count differs: cpu {len(rc)} cuda {len(rg)}"
    print(json.dumps(out))


if __name__ == "__main__":
    main()
