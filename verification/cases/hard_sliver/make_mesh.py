"""Writes sliver_beam.msh (Gmsh MSH 2.2 ASCII): a 0.4 x 0.1 x 0.1 m beam, 8 x 2 x 2 cubes of
6 (Kuhn) tets each, with vertices moved at random (fixed seed) while every tet stays positively
oriented, then a few vertices pushed towards the plane of an opposite face until their tets
are slivers: four well-separated vertices, almost coplanar (volume ~1e-2 of the mean, no short
edge). The end faces x = 0 and x = 0.4 stay planar (the clamp selects x = 0).

    /usr/bin/python3 make_mesh.py     # deterministic; rewrites sliver_beam.msh
"""
from pathlib import Path

import numpy as np

L, B, NX, NY, NZ = 0.4, 0.1, 8, 2, 2
H = L / NX
KUHN = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 5, 7), (0, 4, 6, 7)]


def signed_vol(p, t):
    a, b, c, d = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]], p[t[:, 3]]
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def quality(p, t):
    """(volume, min altitude, longest edge) per tet."""
    v = np.abs(signed_vol(p, t))
    alt = np.full(len(t), np.inf)
    for k in range(4):
        f = np.delete(t, k, axis=1)
        area = 0.5 * np.linalg.norm(np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]), axis=1)
        alt = np.minimum(alt, 3.0 * v / area)
    edges = [np.linalg.norm(p[t[:, i]] - p[t[:, j]], axis=1) for i in range(4) for j in range(i + 1, 4)]
    return v, alt, np.max(edges, axis=0)


def build():
    idx = lambda i, j, k: (i * (NY + 1) + j) * (NZ + 1) + k  # noqa: E731
    pts = np.array([[i * H, j * B / NY, k * B / NZ] for i in range(NX + 1) for j in range(NY + 1)
                    for k in range(NZ + 1)], dtype=float)
    tets = []
    for i in range(NX):
        for j in range(NY):
            for k in range(NZ):
                c = [idx(i + (q & 1), j + ((q >> 1) & 1), k + ((q >> 2) & 1)) for q in range(8)]
                for kt in KUHN:
                    tets.append([c[m] for m in kt])
    tets = np.array(tets)
    vol = signed_vol(pts, tets)
    tets[vol < 0] = tets[vol < 0][:, [0, 2, 1, 3]]
    rng = np.random.default_rng(20261122)
    vmean = np.abs(signed_vol(pts, tets)).mean()
    inc = [np.flatnonzero((tets == n).any(axis=1)) for n in range(len(pts))]
    # 1. Random moves (0.3 h), kept only if every incident tet keeps volume > 0.05 mean.
    for n in range(len(pts)):
        free = [0 < pts[n, 0] < L - 1e-12, 0 < pts[n, 1] < B - 1e-12, 0 < pts[n, 2] < B - 1e-12]
        step = rng.uniform(-0.3, 0.3, 3) * H * np.array(free)
        old = pts[n].copy()
        pts[n] = old + step
        if signed_vol(pts, tets[inc[n]]).min() < 0.05 * vmean:
            pts[n] = old
    # 2. Slivers: push interior vertices towards the plane of the opposite face of one of their
    #    tets until that tet's volume is 1e-2 of the mean (all other tets stay > 0.02 mean).
    interior = [n for n in range(len(pts)) if 0 < pts[n, 0] < L - 1e-9 and 0 < pts[n, 1] < B - 1e-9
                and 0 < pts[n, 2] < B - 1e-9]
    made = 0
    for n in interior:
        for t in inc[n]:
            face = [v for v in tets[t] if v != n]
            a, b, c = pts[face]
            nrm = np.cross(b - a, c - a)
            nrm /= np.linalg.norm(nrm)
            d = np.dot(pts[n] - a, nrm)
            old = pts[n].copy()
            target = 1e-2 * vmean / abs(signed_vol(pts, tets[[t]])[0]) * d
            pts[n] = old - (d - target) * nrm
            v = signed_vol(pts, tets[inc[n]])
            others = v[inc[n] != t]
            if v.min() > 0 and others.min() > 0.02 * vmean:
                made += 1
                break
            pts[n] = old
    return pts, tets, made


def write_msh22(path, pts, tets):
    with open(path, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(pts))
        for i, p in enumerate(pts):
            f.write("%d %.17g %.17g %.17g\n" % (i + 1, *p))
        f.write("$EndNodes\n$Elements\n%d\n" % len(tets))
        for e, t in enumerate(tets):
            f.write("%d 4 2 1 1 %d %d %d %d\n" % (e + 1, *(t + 1)))
        f.write("$EndElements\n")


if __name__ == "__main__":
    pts, tets, made = build()
    write_msh22(Path(__file__).resolve().parent / "sliver_beam.msh", pts, tets)
    v, alt, emax = quality(pts, tets)
    print(f"{len(pts)} vertices, {len(tets)} tets, {made} slivers made; min volume / mean "
          f"{v.min() / v.mean():.3e}; min altitude / h {alt.min() / H:.3e}; "
          f"min (altitude / longest edge) {np.min(alt / emax):.3e}")
