"""Tetrahedral meshes for the FEniCSx reference scripts: Gmsh MSH 4.1 ASCII read/write and
the structured 12-tets-per-hex beam that mirrors qdemsph's `{type: box}` generator.

Why a reader of our own: dolfinx 0.5's `gmshio.read_from_msh` needs the `gmsh` Python module
(Debian `python3-gmsh`), which the project does not install. The format subset written by
`qdemsph mesh` (and by the `gmsh` command line) is small: $Nodes and $Elements blocks, linear
tetrahedra (element type 4). Node tags are kept, so vertex i of the returned arrays is the node
with the i-th smallest tag (qdemsph writes tag = vertex index + 1).

Only numpy is imported here, so the module is usable from any interpreter.
"""
from __future__ import annotations

import numpy as np

TET4 = 4  # Gmsh element type of the 4-node tetrahedron


class MeshFormatError(ValueError):
    pass


def read_msh41(path):
    """Return (points (N,3) float64, tets (M,4) int64 0-based, node_tags (N,) int64).

    Rows of `points` are ordered by node tag; `tets` index those rows. Raises MeshFormatError
    for anything this reader does not understand (binary files, other versions, no tets)."""
    with open(path, "r", encoding="ascii", errors="strict") as f:
        lines = f.read().split("\n")
    pos = 0

    def next_line():
        nonlocal pos
        while pos < len(lines):
            s = lines[pos].strip()
            pos += 1
            if s:
                return s
        raise MeshFormatError(f"{path}: unexpected end of file")

    tags, coords, tets = [], [], []
    seen_nodes = seen_elements = False
    while pos < len(lines):
        s = lines[pos].strip()
        pos += 1
        if s == "$MeshFormat":
            ver, ftype, _ = next_line().split()[:3]
            if not ver.startswith("4.1") or ftype != "0":
                raise MeshFormatError(f"{path}: need MSH 4.1 ASCII, got version {ver} file-type {ftype}")
        elif s == "$Nodes":
            seen_nodes = True
            nblocks = int(next_line().split()[0])
            for _ in range(nblocks):
                _dim, _tag, parametric, nnodes = map(int, next_line().split())
                if parametric:
                    raise MeshFormatError(f"{path}: parametric nodes are not supported")
                btags = [int(next_line()) for _ in range(nnodes)]
                bxyz = [list(map(float, next_line().split()[:3])) for _ in range(nnodes)]
                tags.extend(btags)
                coords.extend(bxyz)
        elif s == "$Elements":
            seen_elements = True
            nblocks = int(next_line().split()[0])
            for _ in range(nblocks):
                _dim, _tag, etype, nelem = map(int, next_line().split())
                rows = [next_line() for _ in range(nelem)]
                if etype == TET4:
                    tets.extend([list(map(int, r.split()[1:5])) for r in rows])
    if not seen_nodes or not seen_elements:
        raise MeshFormatError(f"{path}: no $Nodes or $Elements section (is it a MSH 4.1 ASCII file?)")
    if not tets:
        raise MeshFormatError(f"{path}: no linear tetrahedra (element type 4)")
    tags = np.asarray(tags, dtype=np.int64)
    order = np.argsort(tags, kind="stable")
    tags = tags[order]
    if np.any(np.diff(tags) == 0):
        raise MeshFormatError(f"{path}: duplicate node tags")
    points = np.asarray(coords, dtype=np.float64)[order]
    tag_tets = np.asarray(tets, dtype=np.int64)
    idx = np.searchsorted(tags, tag_tets)
    if np.any(idx >= len(tags)) or np.any(tags[np.minimum(idx, len(tags) - 1)] != tag_tets):
        raise MeshFormatError(f"{path}: an element refers to a node tag that is not defined")
    used = np.unique(idx)
    if len(used) != len(tags):
        # Nodes not used by any tet (e.g. geometry points) would be singular in a solve.
        remap = -np.ones(len(tags), dtype=np.int64)
        remap[used] = np.arange(len(used))
        points, tags, idx = points[used], tags[used], remap[idx]
    return points, idx, tags


def write_msh41(path, points, tets):
    """Write one entity (volume 1, physical group 1) with node tag = index + 1."""
    points = np.asarray(points, dtype=np.float64)
    tets = np.asarray(tets, dtype=np.int64)
    n, m = len(points), len(tets)
    lo, hi = points.min(axis=0), points.max(axis=0)
    with open(path, "w", encoding="ascii") as f:
        f.write("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
        f.write("$PhysicalNames\n1\n3 1 \"body\"\n$EndPhysicalNames\n")
        f.write("$Entities\n0 0 0 1\n")
        f.write(f"1 {lo[0]:.17g} {lo[1]:.17g} {lo[2]:.17g} {hi[0]:.17g} {hi[1]:.17g} {hi[2]:.17g} 1 1 0\n")
        f.write("$EndEntities\n")
        f.write(f"$Nodes\n1 {n} 1 {n}\n3 1 0 {n}\n")
        f.write("".join(f"{i + 1}\n" for i in range(n)))
        f.write("".join(f"{x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in points))
        f.write("$EndNodes\n")
        f.write(f"$Elements\n1 {m} 1 {m}\n3 1 4 {m}\n")
        f.write("".join(f"{e + 1} {a + 1} {b + 1} {c + 1} {d + 1}\n" for e, (a, b, c, d) in enumerate(tets)))
        f.write("$EndElements\n")


def box_mesh(size, cells):
    """Structured box [0,size]: each hex split into 12 tets around a centre vertex.

    Vertices: grid nodes (x fastest) then one centre per hex. Each hex face is cut along the
    diagonal through its lowest-coordinate corner, so shared faces match (conforming).
    Tets are positively oriented. This mirrors qdemsph's box generator only up to the diagonal
    choice: stored references must use the meshes qdemsph exports."""
    (lx, ly, lz), (nx, ny, nz) = size, cells
    xs, ys, zs = (np.linspace(0.0, l, k + 1) for l, k in ((lx, nx), (ly, ny), (lz, nz)))
    gz, gy, gx = np.meshgrid(zs, ys, xs, indexing="ij")
    grid = np.column_stack([gx.ravel(), gy.ravel(), gz.ravel()])

    def node(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i

    # Faces of the unit hex as (corner00, corner10, corner11, corner01) in local (i,j,k) offsets,
    # with corner00 the lowest-coordinate corner; the diagonal is 00-11.
    faces = [
        [(0, 0, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1)], [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)],
        [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)], [(0, 1, 0), (1, 1, 0), (1, 1, 1), (0, 1, 1)],
        [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
    ]
    tris = []
    for a, b, c, d in faces:
        tris += [(a, b, c), (a, c, d)]
    tris = np.array(tris)  # (12, 3, 3) offsets
    ii, jj, kk = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    ii, jj, kk = ii.ravel(), jj.ravel(), kk.ravel()
    nhex = len(ii)
    centre_ids = len(grid) + np.arange(nhex)
    lo = grid[node(ii, jj, kk)]
    hi = grid[node(ii + 1, jj + 1, kk + 1)]
    centres = 0.5 * (lo + hi)
    tets = np.empty((nhex, 12, 4), dtype=np.int64)
    for t, tri in enumerate(tris):
        for v in range(3):
            di, dj, dk = tri[v]
            tets[:, t, v] = node(ii + di, jj + dj, kk + dk)
        tets[:, t, 3] = centre_ids
    tets = tets.reshape(-1, 4)
    points = np.vstack([grid, centres])
    return points, orient_positive(points, tets)


def orient_positive(points, tets):
    tets = np.array(tets, dtype=np.int64, copy=True)
    p = points[tets]
    vol = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    if np.any(np.abs(vol) < 1e-300):
        raise MeshFormatError("degenerate tetrahedron in generated mesh")
    neg = vol < 0
    tets[neg, 1], tets[neg, 2] = tets[neg, 2].copy(), tets[neg, 1].copy()
    return tets


def boundary_triangles(tets):
    """Faces that belong to exactly one tet, as (K,3) vertex index arrays."""
    f = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    key = np.sort(f, axis=1)
    _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return f[cnt[inv.ravel()] == 1]


def face_mean(points, tets, values, axis, coord, tol=1e-9):
    """Area-weighted (P1) mean of nodal `values` over the boundary triangles lying on the plane
    points[:, axis] == coord; returns (mean, area). Exact for P1 fields."""
    tris = boundary_triangles(tets)
    on = np.all(np.abs(points[tris][:, :, axis] - coord) <= tol, axis=1)
    tris = tris[on]
    if len(tris) == 0:
        raise ValueError(f"no boundary triangle on the plane x[{axis}] = {coord}")
    p = points[tris]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    tri_mean = np.asarray(values)[tris].mean(axis=1)
    return float(np.sum(area * tri_mean) / np.sum(area)), float(np.sum(area))


def content_hash(points, tets):
    """sha256 of the mesh content (coordinates rounded to 1e-12, connectivity): stable under
    changes of number formatting in the file, changes when any vertex or tet changes."""
    import hashlib

    h = hashlib.sha256()
    h.update(np.ascontiguousarray(np.round(np.asarray(points, dtype=np.float64), 12) + 0.0).tobytes())
    h.update(np.ascontiguousarray(np.asarray(tets, dtype=np.int64)).tobytes())
    return h.hexdigest()
