"""Post-processing shared by the cantilever cases (nodal fields -> tip deflection etc.)."""
from __future__ import annotations

import numpy as np

from . import paths  # noqa: F401  (puts references/fenicsx on sys.path)
import meshio41  # noqa: E402
from beam_theory import beam_theory  # noqa: E402,F401

E, NU, LENGTH, WIDTH, HEIGHT, TRACTION = 1.0e7, 0.3, 1.0, 0.1, 0.1, -100.0
LOAD = abs(TRACTION) * WIDTH * HEIGHT


def tip_deflection(points, tets, disp, length=LENGTH):
    """Integral mean of uz over the x = L face (exact for a P1 field): the quantity FEniCSx
    reports, so qdemsph and the references are compared like for like."""
    mean, _area = meshio41.face_mean(points, tets, disp[:, 2], axis=0, coord=length, tol=1e-9 * length)
    return mean


def region_mask(points, axis, lo, hi):
    return (points[:, axis] >= lo) & (points[:, axis] <= hi)


def match_vertices(points_a, points_b, scale):
    """Max coordinate mismatch between two vertex lists that must be the same, row by row."""
    if points_a.shape != points_b.shape:
        return np.inf
    return float(np.abs(points_a - points_b).max() / scale)


def last_probe(probes, name):
    """(x, y, z) of probe `name` at the last row of probes.csv."""
    cols = [f"{name}_{c}" for c in "xyz"]
    missing = [c for c in cols if c not in probes]
    if missing:
        raise KeyError(f"probes.csv has no column(s) {missing}; columns: {sorted(probes)}")
    return np.array([probes[c][-1] for c in cols])
