"""Tilts, fall times and front speed of a yade_shogi_chain run (used by the test; run by
hand to read a run made outside pytest, also one still in progress):

    HDF5_USE_FILE_LOCKING=FALSE /usr/bin/python3 chain_analysis.py OUTPUT_DIR... [--json F]

prints for each run the simulated time reached, each piece's fall time (tilt 45 deg), the
front speeds over YADE's windows and YADE's values; --json writes them as records."""
import argparse
import json
import math
import sys
from pathlib import Path

import h5py
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[1]))  # verification/: the harness
import make_yade_chain  # noqa: E402
from harness.shogi import crossing  # noqa: E402

YADE = HERE.parents[2] / "references" / "yade" / "results"
FRONT_TILT = 45.0  # deg: a piece has fallen (YADE's --front-tilt)


def front_speed(fall, pitch, lo, hi):
    """Least-squares slope of the base positions i * pitch against the fall times, pieces
    lo..hi (YADE's definition); None if one of them did not fall."""
    idx = list(range(lo, hi + 1))
    if hi >= len(fall) or any(fall[i] is None for i in idx):
        return None
    return float(np.polyfit([fall[i] for i in idx], [i * pitch for i in idx], 1)[0])


def chain_tilts(out):
    """Times and the tilt (deg, toward -y) of each piece from its probes: the rotation in the
    y-z plane of the line from its centre of mass to the mean of its top vertices (reference
    z >= TOP_Z), added to its initial tilt."""
    with h5py.File(out / "fields.h5", "r") as f:
        p0 = np.asarray(f["mesh/points"], dtype=float)
        body = np.asarray(f["mesh/body"])
    d = np.atleast_1d(np.genfromtxt(out / "probes.csv", delimiter=",", names=True))
    tilts = []
    for b in range(int(body.max()) + 1):  # every piece of the run (YADE's 20-piece variants too)
        q = p0[body == b]
        top0 = q[q[:, 2] >= make_yade_chain.TOP_Z].mean(0)
        com = np.stack([d[f"p{b:02d}_{k}"] for k in "xyz"], 1)
        top = top0 + np.stack([d[f"p{b:02d}top_{k}"] for k in "xyz"], 1)
        v, v0 = top - com, top0 - com[0]
        turn = np.degrees(np.arctan2(-v[:, 1], v[:, 2]) - math.atan2(-v0[1], v0[2]))
        tilts.append(turn + (make_yade_chain.TILT0 if b == 0 else 0.0))
    return d["time"], np.array(tilts)


def analyse(out):
    """One run's record: sizes and cost from summary.json, fall times, front speeds over
    YADE's windows (those every piece of the run covers) with YADE's values."""
    t, tilts = chain_tilts(out)
    fall = [crossing(t, a, FRONT_TILT) for a in tilts]
    s = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    base = json.loads((YADE / "shogi_chain_n40.provenance.json").read_text())["results"]["fall_time_s"]
    last = max((i for i, f in enumerate(fall) if f is not None), default=-1)
    windows = [(10, 38), (5, 18), (5, 35)] + ([(5, last)] if 5 < last < 38 else [])
    speeds = {}
    for lo, hi in windows:
        q = front_speed(fall, make_yade_chain.PITCH, lo, hi)
        if q is not None:
            speeds[f"{lo}..{hi}"] = {"qdemsph": q, "yade_n40": front_speed(base, make_yade_chain.PITCH, lo, hi)}
    return {"run": out.name, "t_reached": float(t[-1]), "pieces": len(fall),
            "fallen": sum(f is not None for f in fall), "fall_time_s": fall, "front_speed_m_s": speeds,
            **{k: s.get(k) for k in ("status", "backend", "n_tets", "dt", "steps", "wall_s")}}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", type=Path, help="qdemsph output folders (finished or in progress)")
    ap.add_argument("--json", type=Path, help="write the records (a list) here")
    a = ap.parse_args()
    recs = []
    for out in a.runs:
        r = analyse(out)
        recs.append(r)
        print(f"{r['run']}: t = {r['t_reached']:.4f} s, fallen {r['fallen']} of {r['pieces']}")
        print("  fall times (s):", " ".join("-" if f is None else f"{f:.4f}" for f in r["fall_time_s"]))
        for w, v in r["front_speed_m_s"].items():
            print(f"  front speed, pieces {w}: qdemsph {v['qdemsph']:.4f} m/s, YADE n40 {v['yade_n40']:.4f} m/s")
    if a.json:
        a.json.write_text(json.dumps(recs, indent=1) + "\n")


if __name__ == "__main__":
    main()
