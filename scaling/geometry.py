#!/usr/bin/python3
"""Partition geometry of a scene on N ranks, without MPI: who owns what, how many items each
rank holds in its halo band, how many tets it computes twice, how many neighbours it talks to.

The scene's items are rebuilt here exactly as the solver places them (box meshes: the 12-tet
split of solver/mesh/box.cpp; SPH: the lattices of solver/sph/fluid_setup.cpp), then cut as the
distributed stepper cuts them (docs/parallel.md; sfc.py is the Python twin of solver/parallel):

  cells     a cubic SfcGrid over the scene, finest cell >= L_cell, refined where the cost
            crowds (max leaf cost = 2 % of the mean rank load), cut along the curve
  costs     per item: tets at their first vertex, vertices, SPH particles, with weights
            (seconds per item per step; default: the calibration measured on the dev machine)
  owner     of a vertex / particle: the rank owning the leaf that holds it
  halo tets a tet is held by every rank owning one of its vertices (home: owner of its
            smallest-id vertex) -> tets computed per rank (redundant work)
  ghosts    vertices, as the distributed stepper sends them (parallel/distributed_backend.cpp
            on the mpi branch): an owned vertex goes to the owners of its tets' other
            vertices ("needed": the vertices of a rank's held tets it does not own) and, if it
            is a contact vertex (on a body surface), to every rank owning a contact vertex in
            the band cells within two cells of its own (band cells of width
            B = 1.5 (2.5 r_prim + D_DEM), r_prim the largest surface-triangle radius).
            SPH particles: to every rank owning a leaf within the kernel
            support 2h of the particle (the band of docs/parallel.md item 2).
  -> ghosts per rank, messages, neighbours, the on/off-node split for nodes of 2..64 ranks.

  /usr/bin/python3 scaling/geometry.py SCENE.yaml --ranks 1,2,4,8 [--curve hilbert]
  /usr/bin/python3 scaling/geometry.py --sweep cubes-weak --backend cpu --ranks 1,2,...,512 --json OUT
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import yaml

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import sfc  # noqa: E402

# Cost weights per item and step (only their ratios matter for the cut): seconds per item on
# one CPU core of the dev machine, rounded (scaling/costs.json "cpu-core-devvm": elements /
# tets, integration / vertices, sph / particles of the single-rank calibration runs).
DEFAULT_WEIGHTS = {"tet": 1.5e-7, "vertex": 1.0e-8, "particle": 2.5e-6}

# 12 tets per hex around the centre: the 6 faces as 4 corners in cyclic order (box.cpp).
_FACES = np.array([
    [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]], [[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]],
    [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]],
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]])


def box_mesh(origin, size, cells):
    """(points (n,3), tets (m,4) int64) of the structured 12-tet box, same numbering as box.cpp."""
    nx, ny, nz = (int(c) for c in cells)
    h = np.asarray(size, float) / np.array([nx, ny, nz])
    o = np.asarray(origin, float)
    k, j, i = np.meshgrid(np.arange(nz + 1), np.arange(ny + 1), np.arange(nx + 1), indexing="ij")
    grid = o + np.stack([i.ravel(), j.ravel(), k.ravel()], 1) * h
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    hexes = np.stack([i.ravel(), j.ravel(), k.ravel()], 1)
    centres = o + (hexes + 0.5) * h
    n_grid = len(grid)
    corner = hexes[:, None, None, :] + _FACES[None]  # (hex, face, 4, 3)
    c = corner[..., 0] + (nx + 1) * (corner[..., 1] + (ny + 1) * corner[..., 2])
    s = np.argmin(c, axis=2)  # diagonal through the smallest index
    idx = (s[..., None] + np.arange(4)) % 4
    a, b, d, e = (np.take_along_axis(c, idx[..., q:q + 1], 2)[..., 0] for q in range(4))
    ctr = (n_grid + np.arange(len(hexes)))[:, None] * np.ones((1, 6), dtype=np.int64)
    t1 = np.stack([a, b, d, ctr], -1)
    t2 = np.stack([a, d, e, ctr], -1)
    tets = np.stack([t1, t2], 2).reshape(-1, 4)  # hex by hex, face by face, 2 per face
    return np.concatenate([grid, centres]), tets.astype(np.int64)


def _lattice(lo, hi, dx):
    return [max(1, int(round((hi[a] - lo[a]) / dx))) for a in range(3)]


def fluid_particles(fluid: dict, gravity) -> np.ndarray:
    """Fluid blocks, tank walls and wall boxes as build_fluid places them."""
    dx = float(fluid["spacing"])
    g = np.asarray(gravity if gravity is not None else [0, 0, 0], float)
    up = int(np.argmax(np.abs(g))) if np.any(g) else 1
    up_pos = not (g[up] > 0)
    out = []
    for b in fluid.get("blocks", []):
        lo = np.asarray(b["min"], float)
        n = _lattice(lo, b["max"], dx)
        k, j, i = np.meshgrid(*(np.arange(m) for m in n[::-1]), indexing="ij")
        out.append(lo + (np.stack([i.ravel(), j.ravel(), k.ravel()], 1) + 0.5) * dx)
    for t in fluid.get("tanks", []):
        lo = np.asarray(t["min"], float)
        n = _lattice(lo, t["max"], dx)
        L = int(t.get("thickness_layers", 3))
        lo_i = [-L] * 3
        hi_i = [n[a] + L for a in range(3)]
        if up_pos:
            hi_i[up] = n[up]
        else:
            lo_i[up] = 0
        k, j, i = np.meshgrid(*(np.arange(lo_i[a], hi_i[a]) for a in (2, 1, 0)), indexing="ij")
        ijk = np.stack([i.ravel(), j.ravel(), k.ravel()], 1)
        inside = np.all((ijk >= 0) & (ijk < np.array(n)), axis=1)
        out.append(lo + (ijk[~inside] + 0.5) * dx)
    for w in fluid.get("walls", []):
        lo = np.asarray(w["min"], float)
        n = _lattice(lo, w["max"], dx)
        k, j, i = np.meshgrid(*(np.arange(m) for m in n[::-1]), indexing="ij")
        out.append(lo + (np.stack([i.ravel(), j.ravel(), k.ravel()], 1) + 0.5) * dx)
    return np.concatenate(out) if out else np.zeros((0, 3))


def box_bodies(scene: dict):
    """(origin, size, cells) of every box body; other mesh types are refused (no gmsh here)."""
    out = []
    for b in scene.get("bodies") or []:
        m = b["mesh"]
        if m.get("type") != "box":
            raise ValueError(f"body '{b.get('name')}': geometry.py handles box meshes only (got {m.get('type')})")
        out.append((m.get("origin", [0, 0, 0]), m["size"], m["cells"]))
    return out


def scene_lcell(scene: dict) -> dict:
    """Band width L_cell = max(tet diameter, contact range, SPH support) and its parts."""
    tet = 0.0
    for _, size, cells in box_bodies(scene):
        h = np.asarray(size, float) / np.asarray(cells, float)
        tet = max(tet, float(np.sort(h)[-2:].dot(np.sort(h)[-2:]) ** 0.5))  # face diagonal
    contact = 0.0
    if len(box_bodies(scene)) > 1 or scene.get("walls"):
        d = float((scene.get("contact") or {}).get("d_dem", 0.1 * tet / math.sqrt(2)))
        contact = 2 * d + tet / 4  # d_dem + default skin (d_dem + r/4), r ~ the primitive size
    sph = 0.0
    if scene.get("fluid"):
        f = scene["fluid"]
        sph = 2 * float(f.get("smoothing", 1.3)) * float(f["spacing"])
    return {"L_cell": max(tet, contact, sph), "tet_diameter": tet, "contact_range": contact, "sph_support": sph}


def contact_band(scene: dict) -> float:
    """Band cell width of the stepper's contact halo: 1.5 (2.5 r_prim + D_DEM), r_prim the
    largest centroid-to-vertex distance of a surface triangle (box faces: two right triangles
    per hex face); 0 when the scene has no contact."""
    bodies = box_bodies(scene)
    if not (len(bodies) > 1 or scene.get("walls")):
        return 0.0
    r = 0.0
    for _, size, cells in bodies:
        h = np.asarray(size, float) / np.asarray(cells, float)
        for a, b in ((h[0], h[1]), (h[0], h[2]), (h[1], h[2])):
            tri = np.array([[0, 0], [a, 0], [a, b]])
            r = max(r, float(np.max(np.linalg.norm(tri - tri.mean(0), axis=1))))
    d = (scene.get("contact") or {}).get("d_dem")
    if d is None:  # 0.1 x the smallest body's mean surface edge
        d = 0.1 * min(float(np.mean(np.asarray(s, float) / np.asarray(c, float))) for _, s, c in bodies)
    return 1.5 * (2.5 * r + float(d))


class SceneItems:
    """All vertices (with tets, in body chunks) and SPH particles of a scene."""

    def __init__(self, scene: dict):
        self.bodies = box_bodies(scene)
        self.lcell = scene_lcell(scene)
        self.band = contact_band(scene)
        pts, surf, self.vert_offset, self.n_tets = [], [], [0], 0
        self._cache = {}
        for o, s, c in self.bodies:
            p, t = self._mesh(tuple(o), tuple(s), tuple(c))
            pts.append(p)
            lo, hi = np.asarray(o, float), np.asarray(o, float) + np.asarray(s, float)
            surf.append(np.any(np.isclose(p, lo, rtol=0, atol=1e-9) | np.isclose(p, hi, rtol=0, atol=1e-9), axis=1))
            self.vert_offset.append(self.vert_offset[-1] + len(p))
            self.n_tets += len(t)
        self.vertices = np.concatenate(pts) if pts else np.zeros((0, 3))
        self.surface = (np.concatenate(surf) if surf else np.zeros(0, bool)) & (self.band > 0)
        self.particles = fluid_particles(scene["fluid"], scene.get("gravity")) if scene.get("fluid") else np.zeros((0, 3))
        self.lo = np.min(np.concatenate([self.vertices, self.particles]), axis=0)
        self.hi = np.max(np.concatenate([self.vertices, self.particles]), axis=0)

    def _mesh(self, o, s, c):
        # Bodies of equal size and cells share one local mesh, shifted.
        key = (s, c)
        if key not in self._cache:
            self._cache[key] = box_mesh((0, 0, 0), s, c)
        p, t = self._cache[key]
        return p + np.asarray(o, float), t

    def tet_chunks(self, max_tets=4_000_000, ranges=False):
        """Global tet connectivity in chunks of whole bodies (with ranges: and the chunk's
        vertex index range [v0, v1))."""
        buf, n, v0 = [], 0, 0
        for bi, (o, s, c) in enumerate(self.bodies):
            _, t = self._cache[(tuple(s), tuple(c))]
            buf.append(t + self.vert_offset[bi])
            n += len(t)
            if n >= max_tets or bi == len(self.bodies) - 1:
                v1 = self.vert_offset[bi + 1]
                yield (np.concatenate(buf), v0, v1) if ranges else np.concatenate(buf)
                buf, n, v0 = [], 0, v1


def _band_destinations(grid, split, pts, own, L, chunk=1_000_000):
    """(item index, destination rank) pairs: the other ranks owning a leaf within L (box
    distance) of an item. Leaves are >= L wide (finest cell >= L), so per axis the cells of
    p - L, p and p + L are all the cells the box [p - L, p + L] meets: 27 samples."""
    items, dests = [], []
    side = np.int64(grid.side)
    for a in range(0, len(pts), chunk):
        p = pts[a:a + chunk]
        o = own[a:a + chunk]
        c = [np.stack([grid.coords(p + s * L * np.eye(3)[ax])[:, ax] for s in (-1, 0, 1)], 1).astype(np.int64)
             for ax in range(3)]  # per axis: (n, 3) cell coordinates of the 3 samples
        cid = (c[0][:, :, None, None] + side * (c[1][:, None, :, None] + side * c[2][:, None, None, :])).reshape(len(p), 27)
        u, inv = np.unique(cid, return_inverse=True)
        uo = sfc.owner_of_key(split, sfc.keys(grid.curve, u % side, (u // side) % side, u // (side * side), grid.order))
        O = uo[inv.reshape(cid.shape)]
        O.sort(axis=1)
        new = np.ones_like(O, dtype=bool)
        new[:, 1:] = O[:, 1:] != O[:, :-1]
        new &= O != o[:, None]
        r, k = np.nonzero(new)
        items.append(r + a)
        dests.append(O[r, k])
    return np.concatenate(items) if items else np.zeros(0, int), np.concatenate(dests) if dests else np.zeros(0, int)


def _band_cells(p, B):
    c = np.floor(p / B).astype(np.int64) + (1 << 20)
    return (c[:, 0] << 42) | (c[:, 1] << 21) | c[:, 2]


def _expand(lo, cnt):
    """Concatenated ranges [lo_i, lo_i + cnt_i)."""
    start = np.repeat(lo - np.concatenate([[0], np.cumsum(cnt)[:-1]]), cnt)
    return start + np.arange(int(cnt.sum()))


def _contact_cell_ranks(pos, own, B, R):
    """The contact band of every occupied band cell: (cells, pairs) with `cells` the sorted
    keys of the band cells holding a contact vertex and `pairs` the sorted values
    cell index x R + rank for every rank owning a contact vertex in the 5^3 cells within two
    cells of it."""
    keys = _band_cells(pos, B)
    cells = np.unique(keys)
    occ = np.unique(np.searchsorted(cells, keys) * R + own.astype(np.int64))  # (cell, owner)
    ok, orank = cells[occ // R], occ % R  # sorted by cell key
    out = []
    for dx in range(-2, 3):
        for dy in range(-2, 3):
            for dz in range(-2, 3):
                nb = cells + (dx << 42) + (dy << 21) + dz
                lo = np.searchsorted(ok, nb, "left")
                cnt = np.searchsorted(ok, nb, "right") - lo
                m = np.nonzero(cnt)[0]
                out.append(np.repeat(m, cnt[m]) * R + orank[_expand(lo[m], cnt[m])])
    return cells, np.unique(np.concatenate(out))


def partition_geometry(scene: dict, nranks: int, curve="hilbert", weights=None, max_leaf=0.02,
                       ranks_per_node=(2, 4, 8), items: SceneItems | None = None) -> dict:
    """Per-rank counts of the partition of `scene` on `nranks` ranks (see the module doc)."""
    w = dict(DEFAULT_WEIGHTS, **(weights or {}))
    it = items or SceneItems(scene)
    L = it.lcell["L_cell"]
    grid = sfc.SfcGrid.covering(curve, it.lo - L, it.hi + L, L)
    nv, npart = len(it.vertices), len(it.particles)
    vkeys = grid.keys(it.vertices) if nv else np.zeros(0, np.uint64)
    pkeys = grid.keys(it.particles) if npart else np.zeros(0, np.uint64)
    # Costs: every vertex, every tet at its first vertex, every particle.
    tets_at = np.zeros(nv)
    for t in it.tet_chunks():
        tets_at += np.bincount(t[:, 0], minlength=nv)
    item_keys = np.concatenate([vkeys, pkeys])
    item_cost = np.concatenate([w["vertex"] + w["tet"] * tets_at, np.full(npart, w["particle"])])
    total = float(item_cost.sum())
    lk, _, _, lc = sfc.refine_cells(curve, grid.order, item_keys, item_cost, max_leaf * total / nranks)
    owner_leaf = sfc.partition_cells(lc, nranks)
    split = sfc.partition_splitters(lk, owner_leaf, nranks)
    vown = sfc.owner_of_key(split, vkeys)
    pown = sfc.owner_of_key(split, pkeys)
    R = nranks
    out = {"ranks": R, "curve": curve, "grid_order": grid.order, "cell": grid.h, "leaves": int(len(lk)),
           "L_cell": L, "lcell_parts": it.lcell, "contact_band": it.band, "weights": w,
           "n_vertices": nv, "n_tets": it.n_tets, "n_particles": npart}
    out["owned_vertices"] = np.bincount(vown, minlength=R)
    out["owned_surface_vertices"] = np.bincount(vown[it.surface], minlength=R)
    out["owned_particles"] = np.bincount(pown, minlength=R)
    # Tets: home (owner of the smallest-id vertex) and held (every owner of a vertex).
    # Ghost vertices: (vertex, rank) pairs, needed by a held tet or sent by the contact band.
    home = np.zeros(R, np.int64)
    held = np.zeros(R, np.int64)
    needed = np.zeros(R, np.int64)
    ghosts = np.zeros(R, np.int64)
    ghosts_surf = np.zeros(R, np.int64)
    vd_all, vsrc_all = [], []
    cr = _contact_cell_ranks(it.vertices[it.surface], vown[it.surface], it.band, R) if R > 1 and it.surface.any() else None
    for t, v0, v1 in it.tet_chunks(ranges=True):
        o = vown[t]  # (m, 4)
        home += np.bincount(o[np.arange(len(t)), np.argmin(t, axis=1)], minlength=R)
        so = np.sort(o, axis=1)
        distinct = np.ones_like(so, dtype=bool)
        distinct[:, 1:] = so[:, 1:] != so[:, :-1]
        held += np.bincount(so[distinct], minlength=R)
        if R == 1:
            continue
        # vertex b of a tet is needed by the owner of vertex a when their owners differ
        cross = ~np.all(o == o[:, :1], axis=1)
        tc, oc = t[cross], o[cross]
        need = [tc[m, b] * R + oc[m, a] for a in range(4) for b in range(4) for m in [oc[:, b] != oc[:, a]]]
        need = np.unique(np.concatenate(need)) if need else np.zeros(0, np.int64)
        needed += np.bincount(need % R, minlength=R)
        pairs = [need]
        if cr is not None:  # contact vertices of this chunk -> ranks in their band
            sv = np.nonzero(it.surface[v0:v1])[0] + v0
            if len(sv):
                cells, cpairs = cr
                ci = np.searchsorted(cells, _band_cells(it.vertices[sv], it.band))  # occupied: found
                lo = np.searchsorted(cpairs, ci * R, "left")
                cnt = np.searchsorted(cpairs, ci * R + R, "left") - lo
                vi = np.repeat(sv, cnt)
                ri = cpairs[_expand(lo, cnt)] % R
                keep = ri != vown[vi]
                pairs.append(vi[keep] * R + ri[keep])
        allp = np.unique(np.concatenate(pairs))  # a vertex is in one chunk only
        dst = allp % R
        src = vown[allp // R]
        ghosts += np.bincount(dst, minlength=R)
        ghosts_surf += np.bincount(dst[it.surface[allp // R]], minlength=R)
        vd_all.append(dst)
        vsrc_all.append(src)
    out["home_tets"], out["held_tets"] = home, held
    out["needed_ghost_vertices"] = needed
    out["ghost_vertices"] = ghosts
    out["ghost_surface_vertices"] = ghosts_surf
    vd = np.concatenate(vd_all) if vd_all else np.zeros(0, np.int64)
    vs = np.concatenate(vsrc_all) if vsrc_all else np.zeros(0, np.int64)
    # SPH particles: the support band.
    pi, pd = _band_destinations(grid, split, it.particles, pown, it.lcell["sph_support"]) if npart and R > 1 \
        else (np.zeros(0, int),) * 2
    out["ghost_particles"] = np.bincount(pd, minlength=R)
    src = np.concatenate([vs, pown[pi]]).astype(np.int64)
    dst = np.concatenate([vd, pd]).astype(np.int64)
    links = np.unique(src * R + dst)
    out["send_neighbours"] = np.bincount(links // R, minlength=R)
    out["recv_neighbours"] = np.bincount(links % R, minlength=R)
    # Ranks r*rpn .. r*rpn + rpn - 1 share a node (consecutive ranks: consecutive pieces).
    for rpn in ranks_per_node or ():
        if R <= rpn:
            continue
        off = (src // rpn) != (dst // rpn)
        out[f"ghost_vertices_offnode_rpn{rpn}"] = np.bincount(vd[off[:len(vd)]], minlength=R)
        out[f"ghost_particles_offnode_rpn{rpn}"] = np.bincount(pd[off[len(vd):]], minlength=R)
        offl = (links // R) // rpn != (links % R) // rpn
        out[f"recv_neighbours_offnode_rpn{rpn}"] = np.bincount((links % R)[offl], minlength=R)
    load = (w["vertex"] * out["owned_vertices"] + w["tet"] * home + w["particle"] * out["owned_particles"]).astype(float)
    out["load"] = load
    out["imbalance_partition"] = float(load.max() / load.mean() - 1) if load.mean() > 0 else 0.0
    # Work per rank including the redundant halo tets (what a rank computes).
    work = w["vertex"] * out["owned_vertices"] + w["tet"] * held + w["particle"] * (out["owned_particles"] + out["ghost_particles"])
    out["work"] = work.astype(float)
    return out


def validate(records: list[dict], curve="hilbert", pairs_one_rank: dict | None = None) -> list[dict]:
    """Halo of measured runs (run.py records of the distributed stepper) against this
    module's prediction for the same scene: ghost vertices x 48 B (x, v per force
    evaluation) vs parallel.halo_bytes_per_step, owned vertices and tets per rank; and the
    contact pairs found (summed over ranks) per 1-rank pairs against the surface held
    (owned + ghost) per owned surface, with the ghost weight k that makes
    pairs(N) / (N pairs(1)) = 1 + k ghost surface / owned surface (pairs_one_rank: sweep ->
    pairs of its 1-rank run, per rank of work)."""
    import scenes
    rows = []
    for r in records:
        p = r.get("parallel") or {}
        if r.get("status") != "ok" or (p.get("ranks") or 1) < 2:
            continue
        sc, _ = scenes.scene_for(r["sweep"], r["ranks"], r["preset"], r.get("variant"))
        g = partition_geometry(sc, r["ranks"], curve)
        pred = int(g["ghost_vertices"].sum() + g["ghost_particles"].sum())
        rows.append({"sweep": r["sweep"], "preset": r["preset"], "ranks": r["ranks"],
                     "measured_halo_bytes_per_step": p["halo_bytes_per_step"],
                     "measured_ghosts_at_48B": p["halo_bytes_per_step"] / 48.0, "predicted_ghosts": pred,
                     "ratio": pred / (p["halo_bytes_per_step"] / 48.0) if p["halo_bytes_per_step"] else None,
                     "measured_owned_vertices": p.get("owned_vertices"), "predicted_owned_vertices": g["owned_vertices"].tolist(),
                     "measured_owned_tets": p.get("owned_tets"), "predicted_home_tets": g["home_tets"].tolist(),
                     "rebalances": p.get("rebalances"), "machine": (r.get("machine") or {}).get("host"),
                     "revision": (r.get("machine") or {}).get("revision")})
        one = (pairs_one_rank or {}).get(r["sweep"])
        pairs = (r.get("items") or {}).get("contact_pairs")
        os_, gs = float(g["owned_surface_vertices"].sum()), float(g["ghost_surface_vertices"].sum())
        if one and pairs and os_ > 0 and gs > 0:
            ratio = pairs / (r["ranks"] * one)
            rows[-1].update({"pairs_measured_per_1rank": ratio, "held_surface_per_owned": (os_ + gs) / os_,
                             "ghost_pair_weight": (ratio - 1) / (gs / os_)})
    return rows


def summarise(g: dict) -> dict:
    """JSON-friendly summary: per-rank lists plus max/mean of each count."""
    s = {}
    for k, v in g.items():
        if isinstance(v, np.ndarray):
            s[k] = v.tolist()
            s[k + "_max"] = float(v.max()) if len(v) else 0.0
            s[k + "_mean"] = float(v.mean()) if len(v) else 0.0
        else:
            s[k] = v
    return s


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", help="a scene YAML (box meshes and/or fluid)")
    ap.add_argument("--sweep", help="a sweep of scenes.py (the scene is generated for each rank count)")
    ap.add_argument("--backend", default="cpu", help="size preset of the sweep (cpu or cuda)")
    ap.add_argument("--ranks", default="1,2,4,8")
    ap.add_argument("--curve", default="hilbert", choices=sfc.CURVES)
    ap.add_argument("--ranks-per-node", default="2,4,8,16,32,64", help="node sizes for the on/off-node split")
    ap.add_argument("--max-items", type=float, default=4e7, help="skip rank counts whose scene has more items")
    ap.add_argument("--json", help="write the per-rank-count summaries here")
    ap.add_argument("--validate", nargs="+", help="run.py records of distributed runs (and the 1-rank run of the "
                    "sweep, for the contact pairs): measured vs predicted halo")
    ap.add_argument("--param", action="append", metavar="KEY=VALUE",
                    help="with --sweep: override a value of the size preset (run.py --param)")
    a = ap.parse_args(argv)
    if a.validate:
        recs = [json.loads(Path(f).read_text()) for f in a.validate]
        one = {r["sweep"]: r["items"]["contact_pairs"] for r in recs
               if r.get("status") == "ok" and r.get("ranks") == 1 and (r.get("items") or {}).get("contact_pairs")}
        rows = validate(recs, a.curve, one)
        for v in rows:
            print(f"{v['sweep']} N={v['ranks']}: halo measured {v['measured_ghosts_at_48B']:.0f} ghosts (at 48 B), "
                  f"predicted {v['predicted_ghosts']} (ratio {v['ratio']:.4f})"
                  + (f"; pairs {v['pairs_measured_per_1rank']:.3f} x 1-rank, held surface "
                     f"{v['held_surface_per_owned']:.3f} x owned: ghost pair weight {v['ghost_pair_weight']:.2f}"
                     if "ghost_pair_weight" in v else ""))
        if a.json:
            Path(a.json).write_text(json.dumps({"what": "halo of the distributed stepper (measured "
                                                        "parallel.halo_bytes_per_step / 48 B) against geometry.py",
                                                "rows": rows}, indent=1) + "\n")
        return
    ranks = [int(x) for x in a.ranks.split(",")]
    rows = []
    for n in ranks:
        if a.sweep:
            import scenes
            scene, meta = scenes.scene_for(a.sweep, n, a.backend, params=scenes.parse_params(a.param))
            if meta["items"] > a.max_items:
                print(f"{a.sweep} N={n}: {meta['items']:.3g} items > --max-items, skipped", flush=True)
                continue
        else:
            scene = yaml.safe_load(Path(a.scene).read_text())
        t0 = time.time()
        g = summarise(partition_geometry(scene, n, a.curve, ranks_per_node=[int(x) for x in a.ranks_per_node.split(",")]))
        g["seconds"] = time.time() - t0
        if a.sweep:
            g["sweep"], g["backend_preset"] = a.sweep, a.backend
        rows.append(g)
        print(f"N={n:4d} tets {g['n_tets']:>10,d} verts {g['n_vertices']:>9,d} particles {g['n_particles']:>9,d} "
              f"| per rank max: owned v {g['owned_vertices_max']:9.0f} held tets {g['held_tets_max']:9.0f} "
              f"(home {g['home_tets_mean']:9.0f} mean) ghosts v {g['ghost_vertices_max']:7.0f} p {g['ghost_particles_max']:7.0f} "
              f"needed v {g['needed_ghost_vertices_max']:6.0f} nbrs {g['recv_neighbours_max']:3.0f} "
              f"imb {100 * g['imbalance_partition']:.2f} % [{g['seconds']:.1f} s]", flush=True)
    if a.json:
        doc = {"what": "partition geometry (scaling/geometry.py): SFC pieces, halo band, halo tets; "
                       "geometry only, no timing", "curve": a.curve, "sweep": a.sweep, "backend_preset": a.backend,
               "rows": rows}
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(doc) + "\n")


if __name__ == "__main__":
    main()
