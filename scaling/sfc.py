"""Python twin of solver/parallel/{sfc.hpp, cell_tree.cpp, partition.cpp} (numpy, vectorised).

Used by geometry.py to compute the pieces the distributed stepper would make for a scene
(who owns which item, how many items sit in each rank's halo band) without running MPI, and by
model.py for the halo term at rank counts no machine here has. Same rules as the C++:

  keys       Morton (interleaved bits, x most significant), Hilbert (Skilling's transpose
             method), Peano (3^k serpentine); `keys(curve, x, y, z, order)` on integer arrays
  refine     `refine_cells(curve, order, item_keys, item_cost, max_cost, min_level)`: leaves of
             the cell tree in curve order (key, span, level, cost)
  partition  `partition_cells(costs, nranks)`: cell i -> floor(n (P_i + c_i / 2) / W), owners
             never decrease; `partition_splitters` / `owner_of_key` map any key to its owner

tests/test_sfc.py compiles the C++ headers and sources with g++ and checks that both agree
key for key and owner for owner.
"""
from __future__ import annotations

import numpy as np

CURVES = ("morton", "hilbert", "peano")


def curve_base(curve: str) -> int:
    return 3 if curve == "peano" else 2


def curve_max_order(curve: str) -> int:
    return 13 if curve == "peano" else 21


def _u64(a):
    return np.asarray(a, dtype=np.uint64)


def spread3(v):
    """Bit i of the low 21 bits moves to bit 3i (sfc_spread3)."""
    v = _u64(v) & np.uint64(0x1FFFFF)
    v = (v | (v << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
    v = (v | (v << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
    v = (v | (v << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
    v = (v | (v << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    v = (v | (v << np.uint64(2))) & np.uint64(0x1249249249249249)
    return v


def morton_keys(x, y, z):
    return (spread3(x) << np.uint64(2)) | (spread3(y) << np.uint64(1)) | spread3(z)


def hilbert_keys(x, y, z, order: int):
    X = [np.array(x, dtype=np.uint64, copy=True), np.array(y, dtype=np.uint64, copy=True),
         np.array(z, dtype=np.uint64, copy=True)]
    M = 1 << (order - 1)
    Q = M
    while Q > 1:  # inverse undo
        P, q = np.uint64(Q - 1), np.uint64(Q)
        for i in range(3):
            hit = (X[i] & q) != 0
            if i == 0:
                X[0] = np.where(hit, X[0] ^ P, X[0])
                continue
            t = np.where(hit, np.uint64(0), (X[0] ^ X[i]) & P)
            X[0] = np.where(hit, X[0] ^ P, X[0] ^ t)
            X[i] = X[i] ^ t
        Q >>= 1
    X[1] ^= X[0]  # Gray encode
    X[2] ^= X[1]
    t = np.zeros_like(X[0])
    Q = M
    while Q > 1:
        t = np.where((X[2] & np.uint64(Q)) != 0, t ^ np.uint64(Q - 1), t)
        Q >>= 1
    return morton_keys(X[0] ^ t, X[1] ^ t, X[2] ^ t)


def peano_keys(x, y, z, order: int):
    c = [_u64(x), _u64(y), _u64(z)]
    parity = [np.zeros(c[0].shape, dtype=np.uint64) for _ in range(3)]
    key = np.zeros(c[0].shape, dtype=np.uint64)
    scale = 3 ** (order - 1)
    for _ in range(order):
        s = np.uint64(scale)
        for a in range(3):
            cd = (c[a] // s) % np.uint64(3)
            others = parity[0] ^ parity[1] ^ parity[2] ^ parity[a]
            kd = np.where(others != 0, np.uint64(2) - cd, cd)
            key = key * np.uint64(3) + kd
            parity[a] = parity[a] ^ (kd & np.uint64(1))
        scale //= 3
    return key


def keys(curve: str, x, y, z, order: int):
    """Key of integer cells (x, y, z) on a grid of curve_base^order cells per axis."""
    if curve == "morton":
        return morton_keys(x, y, z)
    if curve == "hilbert":
        return hilbert_keys(x, y, z, order)
    if curve == "peano":
        return peano_keys(x, y, z, order)
    raise ValueError(f"unknown curve '{curve}' (one of {', '.join(CURVES)})")


class SfcGrid:
    """Positions -> finest cells of [lo, lo + side h)^3 -> keys (SfcGrid in cell_tree.hpp)."""

    def __init__(self, curve: str, order: int, lo, h: float):
        self.curve, self.order, self.lo, self.h = curve, int(order), np.asarray(lo, float), float(h)
        self.side = curve_base(curve) ** self.order

    @classmethod
    def covering(cls, curve: str, lo, hi, min_cell: float):
        """The finest grid whose cells are at least min_cell wide and that covers [lo, hi]."""
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        extent = float(np.max(hi - lo)) * (1 + 1e-9) + 1e-12
        b = curve_base(curve)
        order = 1
        while order < curve_max_order(curve) and extent / b ** (order + 1) >= min_cell:
            order += 1
        return cls(curve, order, lo, extent / b ** order)

    def coords(self, p):
        c = np.floor((np.asarray(p, float) - self.lo) / self.h)
        return np.clip(c, 0, self.side - 1).astype(np.uint64)

    def keys(self, p):
        c = self.coords(p)
        return keys(self.curve, c[..., 0], c[..., 1], c[..., 2], self.order)


def refine_cells(curve: str, order: int, item_keys, item_cost, max_cost: float, min_level: int = 0):
    """Leaves of the refined cell tree in curve order: (key, span, level, cost) arrays."""
    if not 1 <= order <= curve_max_order(curve):
        raise ValueError(f"refine_cells: order {order} outside [1, {curve_max_order(curve)}]")
    item_keys = _u64(item_keys)
    item_cost = np.asarray(item_cost, float)
    if item_keys.shape != item_cost.shape:
        raise ValueError("refine_cells: keys and costs differ in size")
    idx = np.argsort(item_keys, kind="stable")
    k = item_keys[idx]
    prefix = np.concatenate([[0.0], np.cumsum(item_cost[idx])])
    nb = curve_base(curve) ** 3
    out_key, out_span, out_level, out_cost = [], [], [], []
    # Iterative depth-first visit in curve order (children pushed in reverse).
    stack = [(0, nb ** order, 0)]
    while stack:
        k0, span, level = stack.pop()
        a = np.searchsorted(k, np.uint64(k0), "left")
        b = np.searchsorted(k, np.uint64(k0 + span), "left") if k0 + span < 2 ** 64 else len(k)
        c = prefix[b] - prefix[a]
        if level < order and (level < min_level or c > max_cost):
            child = span // nb
            for j in reversed(range(nb)):
                stack.append((k0 + j * child, child, level + 1))
            continue
        out_key.append(k0)
        out_span.append(span)
        out_level.append(level)
        out_cost.append(c)
    return (np.array(out_key, dtype=np.uint64), np.array(out_span, dtype=np.uint64),
            np.array(out_level, dtype=np.int32), np.array(out_cost, dtype=float))


def partition_cells(cost, nranks: int):
    """Owner per cell (cells in curve order): floor(n (P_i + c_i / 2) / W), non-decreasing."""
    if nranks < 1:
        raise ValueError("partition_cells: nranks must be >= 1")
    cost = np.asarray(cost, float)
    if np.any(~np.isfinite(cost)) or np.any(cost < 0):
        raise ValueError("partition_cells: a cost is negative or not finite")
    n = len(cost)
    if n == 0 or nranks == 1:
        return np.zeros(n, dtype=np.int64)
    total = float(np.cumsum(cost)[-1])  # summed in order, as the C++ (same rounding)
    c = cost if total > 0 else np.ones(n)
    W = total if total > 0 else float(n)
    before = np.concatenate([[0.0], np.cumsum(c)[:-1]])
    r = np.floor((before + 0.5 * c) * nranks / W).astype(np.int64)
    return np.minimum(np.maximum.accumulate(np.maximum(r, 0)), nranks - 1)


def partition_splitters(cell_keys, owner, nranks: int):
    """First key of each rank's piece (nranks + 1 entries, last = 2^64 - 1)."""
    end = np.iinfo(np.uint64).max
    s = np.full(nranks + 1, end, dtype=np.uint64)
    cell_keys, owner = _u64(cell_keys), np.asarray(owner)
    ranks, first_cell = np.unique(owner, return_index=True)
    s[ranks] = cell_keys[first_cell]
    s = np.minimum.accumulate(s[::-1])[::-1].copy()  # a rank without cells: the next one's
    first = int(owner[0]) if len(owner) else 0
    s[: first + 1] = 0
    return s


def owner_of_key(splitters, k):
    """The last rank r with splitters[r] <= key (vectorised over keys)."""
    return np.searchsorted(splitters[:-1], _u64(k), side="right") - 1


def partition_stats(cost, owner, nranks: int):
    load = np.bincount(np.asarray(owner), weights=np.asarray(cost, float), minlength=nranks)
    mean = load.sum() / nranks if nranks else 0.0
    mx = float(load.max()) if len(load) else 0.0
    return {"load": load, "mean": mean, "max": mx, "imbalance": mx / mean - 1 if mean > 0 else 0.0}
