"""Shogi-piece measurements shared by the YADE comparison cases: the tilt of each piece from
a rigid (Kabsch) fit of its vertex positions in fields.h5, and tilt-crossing times. Tilt =
signed angle of a piece's height axis from vertical in the y-z plane, positive toward -y
(qdemsph's pieces fall toward -y; YADE's toward +x, with the same sign convention)."""
import math

import h5py
import numpy as np


def crossing(t, a, level):
    """First time a rises through level (linear interpolation), None if never."""
    a = np.asarray(a)
    i = np.flatnonzero((a[:-1] < level) & (a[1:] >= level))
    if not i.size:
        return None
    k = i[0]
    return float(t[k] + (level - a[k]) * (t[k + 1] - t[k]) / (a[k + 1] - a[k]))


def height_axis(tilt_deg):
    """Unit height axis of a piece tilted by tilt_deg toward -y."""
    a = math.radians(tilt_deg)
    return np.array([0.0, -math.sin(a), math.cos(a)])


def tilt_history(fields_h5, tilts0):
    """Times, tilt (deg) of each body b < len(tilts0) whose initial tilt is tilts0[b], the
    reference points and the body index of each point. Each body's rotation is the rigid
    (Kabsch) fit of its vertex positions to their initial ones; the tilt is that rotation
    applied to the initial height axis."""
    with h5py.File(fields_h5, "r") as f:
        p0 = np.asarray(f["mesh/points"], dtype=float)
        body = np.asarray(f["mesh/body"])
        steps = sorted(f["steps"].keys())
        t = np.array([float(f["steps"][k].attrs["time"]) for k in steps])
        xs = [np.asarray(f["steps"][k]["position"], dtype=float) for k in steps]
    tilts = []
    for b, tilt0 in enumerate(tilts0):
        a0 = height_axis(tilt0)
        idx = np.flatnonzero(body == b)
        q0 = p0[idx] - p0[idx].mean(0)
        out = []
        for x in xs:
            q = x[idx] - x[idx].mean(0)
            u, _, vt = np.linalg.svd(q0.T @ q)
            d = np.sign(np.linalg.det(vt.T @ u.T))
            a = vt.T @ np.diag([1.0, 1.0, d]) @ u.T @ a0
            out.append(math.degrees(math.atan2(-a[1], a[2])))
        tilts.append(np.array(out))
    return t, tilts, p0, body
