"""Readers for the SPH outputs of a qdemsph run: DIR/fluid.h5 (point-cloud frames) and
DIR/fluid.csv (per-probe-row fluid statistics). See solver/io/fluid_h5.hpp."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def fluid_frames(out, most=None):
    """List of dicts {time, x (N,3), v (N,3), p (N), rho (N), type (N), id (N)}, fluid and wall
    particles, in file order. most: only up to that many frames, spread evenly over the run
    (first and last included), the others not read (pictures of large runs)."""
    import h5py

    frames = []
    with h5py.File(Path(out) / "fluid.h5", "r") as f:
        keys = sorted(f["steps"].keys())
        if most is not None:
            keys = [keys[i] for i in np.unique(np.linspace(0, len(keys) - 1, min(most, len(keys))).round().astype(int))]
        for k in keys:
            s = f["steps"][k]
            frames.append({"time": float(s.attrs["time"]), "x": s["position"][:], "v": s["velocity"][:],
                           "p": s["pressure"][:], "rho": s["density"][:], "type": s["type"][:],
                           "id": s["id"][:]})
    return frames


def fluid_csv(out):
    """fluid.csv as {column: 1-D array}."""
    data = np.atleast_1d(np.genfromtxt(Path(out) / "fluid.csv", delimiter=",", names=True, dtype=float))
    return {n: np.asarray(data[n]) for n in data.dtype.names}


def water_level(frame, x0, dx, up=1):
    """Height of the highest fluid particle within |x - x0| < dx (0 when none), plus dx/2 for
    the particle's own extent."""
    fl = frame["type"] == 0
    sel = fl & (np.abs(frame["x"][:, 0] - x0) < dx)
    return float(frame["x"][sel, up].max() + 0.5 * dx) if sel.any() else 0.0


def rms(a):
    a = np.asarray(a, dtype=float)
    return float(np.sqrt(np.mean(a * a)))
