"""Tilts, fall times and front speed of a yade_shogi_chain run (used by the test; run by
hand to read a run made outside pytest, also one still in progress):

    HDF5_USE_FILE_LOCKING=FALSE /usr/bin/python3 chain_analysis.py OUTPUT_DIR

prints the simulated time reached, each piece's fall time (tilt 45 deg), the front speeds
over YADE's windows and YADE's values."""
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
    if any(fall[i] is None for i in idx):
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
    for b in range(make_yade_chain.N):
        q = p0[body == b]
        top0 = q[q[:, 2] >= make_yade_chain.TOP_Z].mean(0)
        com = np.stack([d[f"p{b:02d}_{k}"] for k in "xyz"], 1)
        top = top0 + np.stack([d[f"p{b:02d}top_{k}"] for k in "xyz"], 1)
        v, v0 = top - com, top0 - com[0]
        turn = np.degrees(np.arctan2(-v[:, 1], v[:, 2]) - math.atan2(-v0[1], v0[2]))
        tilts.append(turn + (make_yade_chain.TILT0 if b == 0 else 0.0))
    return d["time"], np.array(tilts)


def main(out):
    t, tilts = chain_tilts(Path(out))
    fall = [crossing(t, a, FRONT_TILT) for a in tilts]
    print(f"t = {t[-1]:.4f} s, fallen {sum(f is not None for f in fall)} of {len(fall)}")
    print("fall times (s):", " ".join("-" if f is None else f"{f:.4f}" for f in fall))
    base = json.loads((YADE / "shogi_chain_n40.provenance.json").read_text())["results"]["fall_time_s"]
    for lo, hi in ((10, 38), (5, 18), (5, 35)):
        q = front_speed(fall, make_yade_chain.PITCH, lo, hi)
        y = front_speed(base, make_yade_chain.PITCH, lo, hi)
        print(f"front speed, pieces {lo}..{hi}: qdemsph {'-' if q is None else f'{q:.4f}'} m/s, YADE n40 {y:.4f} m/s")
    last = max((i for i, f in enumerate(fall) if f is not None), default=-1)
    if 5 < last < 38:  # a run in progress: the front so far
        q = front_speed(fall, make_yade_chain.PITCH, 5, last)
        y = front_speed(base, make_yade_chain.PITCH, 5, last)
        print(f"front speed so far, pieces 5..{last}: qdemsph {q:.4f} m/s, YADE n40 {y:.4f} m/s")


if __name__ == "__main__":
    main(sys.argv[1])
