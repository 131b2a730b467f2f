#!/usr/bin/python3
"""Scaling scenes and sweep definitions.

Three weak-scaling cases (the problem grows with the rank count, the work per rank stays the
same) and their strong-scaling twins (one fixed problem on more ranks):

  cubes     the report's 27-cube static block (verification/cases/contact_stack: 1 m cubes of
            8 x 8 x 8 hexes = 6,144 tets, 3 high, gap = D_DEM, E 1e7, mu 0.5, on a floor plane)
            grown horizontally: columns of 3 cubes on an nx x ny grid, cubes per rank constant.
            cpu preset: 27 cubes per rank (1 rank = the report's 27-cube stack, 165,888 tets);
            cuda preset: 216 cubes per rank (1.33 M tets per GPU: a GPU needs ~1 M items to be
            busy; METHOD.md section 4 / the report: 6.75 cubes per process at 512 processes).
  dambreak  an SPH dam break (water 1.0 x 0.5 m at one end of a 2.0 m long channel: floor and
            end walls of 3 particle layers) widened in z with the rank count (flow along x,
            open in z so that the work per unit width is the same at every width).
  topple    rows of box dominoes (0.3 x 1.0 x 2.0 m, 768 tets, pitch 0.8 m) on a floor, every
            4th one pushed over at the start so that toppling fronts run all along the rows;
            the rows lengthened with the rank count: contact-heavy and moving.
  slide-balance: a block of cubes (2 high) sliding at 6 m/s along a floor into an end wall
            1.5 m ahead (hit at ~0.27 s, run 0.45 s), on a fixed rank count with the load balancer on and off: the load
            crosses the domain, so the first cut goes stale (solids only: runs today).
  dambreak-balance: a coarse dam break in a closed tank, run long enough (0.6 s) for the surge
            to cross it, on a fixed rank count with the load balancer on and off (static
            partition).

Efficiency: weak E(N) = t(N_ref) / t(N) with t the time per step (N_ref = 1, and 8 as in the
report); strong E(N) = N_ref t(N_ref) / (N t(N)).

  /usr/bin/python3 scaling/scenes.py cubes-weak --ranks 4 --backend cpu > scene.yaml
  /usr/bin/python3 scaling/scenes.py --list
"""
from __future__ import annotations

import argparse
import json
import math
import sys

try:  # PyYAML for readable scenes; without it (bare GPU machines) JSON, which is YAML too
    import yaml
except ImportError:
    yaml = None

# The scene keys of the distributed stepper's `parallel:` block used by the sweeps (one
# place, so that a renamed key is one edit; docs/scene-format.md on the mpi branch: curve,
# rebalance_threshold (0.10), rebalance_every (100 steps), max_cell_cost). `balanced`: the
# defaults; `static`: the first partition is kept (vertices still migrate to the owners of
# the pieces they move into, but the pieces are never re-cut).
PARALLEL_KEYS = {"curve": "curve", "threshold": "rebalance_threshold", "every": "rebalance_every"}
VARIANTS = {
    "balanced": {},
    "static": {PARALLEL_KEYS["threshold"]: 1.0e9},
}

# gap: D_DEM, the vertical gap (each cube starts resting on the one below at the contact
# distance); side_gap: 1.5 D_DEM between columns. With the side gap also at D_DEM every side
# face sat exactly at the contact threshold, and the rounding of the cubes' origins decided
# which touched: 4,023 contacts on 1 rank, 32 x that per rank on 8 (2026-11-22 records), so
# the work per rank was not constant. 1.5 D_DEM keeps the side pairs in the candidate lists
# (skin) but out of contact.
CUBE = {"size": 1.0, "gap": 0.01, "side_gap": 0.015, "height": 3}
DOMINO = {"size": [0.3, 1.0, 2.0], "cells": [2, 4, 8], "pitch": 0.8, "row_spacing": 1.5, "omega": 3.0}


def _grid2(c: int):
    """nx >= ny with nx * ny = c, as square as the divisors allow."""
    ny = max(d for d in range(1, int(math.isqrt(c)) + 1) if c % d == 0)
    return c // ny, ny


def cube_block(columns: int, cells: int = 8, height: int = CUBE["height"]):
    """`columns` columns of `height` cubes on a near-square horizontal grid."""
    nx, ny = _grid2(columns)
    s, gap, side = CUBE["size"], CUBE["gap"], CUBE["side_gap"]
    bodies = []
    for k in range(height):
        for j in range(ny):
            for i in range(nx):
                o = [round(i * (s + side), 6), round(j * (s + side), 6), round(gap + k * (s + gap), 6)]
                bodies.append({"name": f"c{i}_{j}_{k}", "material": "block",
                               "mesh": {"type": "box", "origin": o, "size": [s, s, s], "cells": [cells] * 3}})
    scene = {"name": f"cubes_{columns}x{height}", "run": {"end_time": 0.01}, "gravity": [0, 0, -9.81],
             "materials": {"block": {"E": 1.0e7, "nu": 0.3, "density": 1000, "viscosity": 2000}},
             "contact": {"mu": 0.5, "restitution": 0.3, "d_dem": gap},
             "walls": [{"point": [0, 0, 0], "normal": [0, 0, 1], "mu": 0.5}],
             "bodies": bodies, "output": {"fields_every": 0, "probes_every": 0}}
    n = len(bodies)
    meta = {"layout": [nx, ny, height], "bodies": n, "n_tets": n * 12 * cells ** 3,
            "n_vertices": n * ((cells + 1) ** 3 + cells ** 3), "n_particles": 0}
    return scene, meta


def sliding_block(nx: int, ny: int, cells: int = 4, layers: int = 2, speed: float = 6.0, run_out: float = 1.5):
    """nx x ny x `layers` cubes (1 m, `cells`^3 hexes) sliding at `speed` along +x on a floor
    (mu 0.1) into an end wall `run_out` m ahead: the whole load travels across the domain, so a
    partition cut at the start goes stale (the balancer case for solids)."""
    s, gap = CUBE["size"], CUBE["gap"]
    bodies = []
    for k in range(layers):
        for j in range(ny):
            for i in range(nx):
                o = [round(i * (s + gap), 6), round(j * (s + gap), 6), round(gap + k * (s + gap), 6)]
                bodies.append({"name": f"s{i}_{j}_{k}", "material": "block", "velocity": [speed, 0, 0],
                               "mesh": {"type": "box", "origin": o, "size": [s, s, s], "cells": [cells] * 3}})
    end = round(nx * (s + gap) + run_out, 6)
    scene = {"name": f"slide_{nx}x{ny}x{layers}", "run": {"end_time": 0.01}, "gravity": [0, 0, -9.81],
             "materials": {"block": {"E": 1.0e7, "nu": 0.3, "density": 1000, "viscosity": 2000}},
             "contact": {"mu": 0.1, "restitution": 0.3, "d_dem": gap},
             "walls": [{"point": [0, 0, 0], "normal": [0, 0, 1], "mu": 0.1},
                       {"point": [end, 0, 0], "normal": [-1, 0, 0], "mu": 0.1}],
             "bodies": bodies, "output": {"fields_every": 0, "probes_every": 0}}
    n = len(bodies)
    return scene, {"layout": [nx, ny, layers], "bodies": n, "n_tets": n * 12 * cells ** 3,
                   "n_vertices": n * ((cells + 1) ** 3 + cells ** 3), "n_particles": 0}


def _lattice_count(lo, hi, dx):
    return math.prod(max(1, round((hi[a] - lo[a]) / dx)) for a in range(3))


def dam_break(width: float, dx: float, closed: bool = False, length=2.0, column=(1.0, 0.5), tank_height=0.6):
    """A column of water (column[0] long, column[1] high, `width` wide in z) at one end of a
    `length` x `tank_height` tank. closed: a tank with walls on all sides (3 layers); open: a
    channel section, floor and end walls only, open in z, so that the work per unit width is
    the same at every width (weak scaling; the edges spill about g t^2 / 2, 2 cm in 0.06 s)."""
    L = 3
    block = ([0, 0, 0], [column[0], column[1], width])
    fluid = {"spacing": dx, "viscosity": 0.02, "wall_viscosity": False, "delta": 0.1,
             "blocks": [{"min": block[0], "max": block[1]}]}
    nf = _lattice_count(*block, dx)
    if closed:
        fluid["tanks"] = [{"min": [0, 0, 0], "max": [length, tank_height, width], "thickness_layers": L}]
        t = [max(1, round(v / dx)) for v in (length, tank_height, width)]
        nw = (t[0] + 2 * L) * (t[1] + L) * (t[2] + 2 * L) - t[0] * t[1] * t[2]
    else:
        d = L * dx
        walls = [([-d, -d, 0], [length + d, 0, width]),  # floor
                 ([-d, 0, 0], [0, tank_height, width]), ([length, 0, 0], [length + d, tank_height, width])]
        fluid["walls"] = [{"min": [round(v, 9) for v in lo], "max": [round(v, 9) for v in hi]} for lo, hi in walls]
        nw = sum(_lattice_count(lo, hi, dx) for lo, hi in walls)
    scene = {"name": f"dambreak_w{width:g}", "run": {"end_time": 0.01}, "gravity": [0, -9.81, 0],
             "fluid": fluid, "output": {"fields_every": 0, "probes_every": 0}}
    return scene, {"layout": [width], "closed": closed, "bodies": 0, "n_tets": 0, "n_vertices": 0,
                   "n_particles": nf + nw, "n_fluid": nf, "n_wall": nw}


def domino_rows(per_row: int, rows: int, push_every: int = 4):
    """`rows` parallel rows of `per_row` dominoes, every `push_every`-th one (from the first)
    starting to tip about its front base edge at omega, so that toppling fronts start all
    along the rows (the same work per unit length; push_every = per_row: one wave per row)."""
    t, w, H = DOMINO["size"]
    p, rs, om = DOMINO["pitch"], DOMINO["row_spacing"], DOMINO["omega"]
    gap = 0.005
    bodies = []
    for r in range(rows):
        for i in range(per_row):
            b = {"name": f"d{r}_{i}", "material": "wood",
                 "mesh": {"type": "box", "origin": [round(i * p, 6), round(r * rs, 6), gap],
                          "size": [t, w, H], "cells": DOMINO["cells"]}}
            if i % push_every == 0:
                # rotation about the front base edge: v_com = omega y x (com - edge)
                b["velocity"] = [round(om * H / 2, 6), 0, round(om * t / 2, 6)]
                b["angular_velocity"] = [0, om, 0]
            bodies.append(b)
    scene = {"name": f"topple_{rows}x{per_row}", "run": {"end_time": 0.01}, "gravity": [0, 0, -9.81],
             "materials": {"wood": {"E": 1.0e7, "nu": 0.3, "density": 700, "viscosity": 500}},
             "contact": {"mu": 0.3, "restitution": 0.5, "d_dem": gap},
             "walls": [{"point": [0, 0, 0], "normal": [0, 0, 1], "mu": 0.5}],
             "bodies": bodies, "output": {"fields_every": 0, "probes_every": 0}}
    c = DOMINO["cells"]
    n = len(bodies)
    hexes = c[0] * c[1] * c[2]
    return scene, {"layout": [per_row, rows], "bodies": n, "n_tets": 12 * n * hexes,
                   "n_vertices": n * ((c[0] + 1) * (c[1] + 1) * (c[2] + 1) + hexes), "n_particles": 0}


# Sweeps: what grows with N (weak) or stays (strong), per backend preset. `steps`: timed steps
# (end_time = steps x dt, dt taken once from `qdemsph info` of the 1-rank scene and fixed);
# `end_time` instead when the physics needs a duration.
SWEEPS = {
    "cubes-weak": {"case": "cubes", "mode": "weak", "ranks": [1, 2, 4, 8, 16, 32],
                   "presets": {"cpu": {"cubes_per_rank": 27, "cells": 8, "steps": 20},
                               "cuda": {"cubes_per_rank": 216, "cells": 8, "steps": 200}}},
    "cubes-strong": {"case": "cubes", "mode": "strong", "ranks": [1, 2, 4, 8, 16, 32],
                     "presets": {"cpu": {"cubes": 108, "cells": 8, "steps": 10},
                                 "cuda": {"cubes": 432, "cells": 8, "steps": 200}}},
    "dambreak-weak": {"case": "dambreak", "mode": "weak", "ranks": [1, 2, 4, 8, 16, 32],
                      "presets": {"cpu": {"width_per_rank": 0.2, "dx": 0.02, "steps": 40},
                                  "cuda": {"width_per_rank": 0.25, "dx": 0.005, "steps": 300}}},
    "dambreak-strong": {"case": "dambreak", "mode": "strong", "ranks": [1, 2, 4, 8, 16, 32],
                        "presets": {"cpu": {"width": 0.8, "dx": 0.02, "steps": 20},
                                    "cuda": {"width": 0.5, "dx": 0.005, "steps": 300}}},
    "topple-weak": {"case": "topple", "mode": "weak", "ranks": [1, 2, 4, 8, 16, 32],
                    "presets": {"cpu": {"per_rank": 32, "rows": 4, "end_time": 0.25},
                                "cuda": {"per_rank": 1024, "rows": 16, "end_time": 0.25}}},
    "slide-balance": {"case": "slide", "mode": "strong", "ranks": [4, 8], "variants": ["balanced", "static"],
                      "presets": {"cpu": {"nx": 4, "ny": 3, "cells": 4, "end_time": 0.45},
                                  "cuda": {"nx": 32, "ny": 16, "cells": 4, "end_time": 0.45}}},
    "dambreak-balance": {"case": "dambreak", "mode": "strong", "ranks": [4, 8],
                         "variants": ["balanced", "static"],
                         "presets": {"cpu": {"width": 0.8, "dx": 0.04, "end_time": 0.6, "closed": True},
                                     "cuda": {"width": 0.5, "dx": 0.01, "end_time": 0.6, "closed": True}}},
}


def parse_params(items) -> dict:
    """--param KEY=VALUE (repeatable) -> {KEY: number or string}: preset values to override."""
    out = {}
    for it in items or []:
        k, sep, v = it.partition("=")
        if not sep or not k:
            raise ValueError(f"--param {it!r}: expected KEY=VALUE, e.g. cubes_per_rank=864")
        try:
            out[k] = int(v)
        except ValueError:
            try:
                out[k] = float(v)
            except ValueError:
                out[k] = v
    return out


def scene_for(sweep: str, ranks: int, backend: str = "cpu", variant: str | None = None, params: dict | None = None):
    """(scene dict, meta) of `sweep` at `ranks` ranks with the `backend` size preset, whose
    values `params` may override (e.g. {"cubes_per_rank": 864}: another size per rank). meta:
    sizes (n_tets, n_vertices, n_particles, bodies, items), layout, steps or end_time."""
    if sweep not in SWEEPS:
        raise KeyError(f"unknown sweep '{sweep}' (known: {', '.join(SWEEPS)})")
    sw = SWEEPS[sweep]
    if backend not in sw["presets"]:
        raise KeyError(f"sweep '{sweep}' has no '{backend}' preset")
    p = sw["presets"][backend]
    unknown = sorted(set(params or {}) - set(p))
    if unknown:
        raise KeyError(f"sweep '{sweep}' ({backend} preset) has no parameter {', '.join(unknown)} "
                       f"(known: {', '.join(p)})")
    p = {**p, **(params or {})}
    weak = sw["mode"] == "weak"
    if sw["case"] == "cubes":
        cubes = p["cubes_per_rank"] * ranks if weak else p["cubes"]
        if cubes % CUBE["height"]:
            raise ValueError(f"{sweep}: {cubes} cubes is not a whole number of columns of {CUBE['height']}")
        scene, meta = cube_block(cubes // CUBE["height"], p["cells"])
    elif sw["case"] == "dambreak":
        width = p["width_per_rank"] * ranks if weak else p["width"]
        scene, meta = dam_break(round(width, 9), p["dx"], closed=p.get("closed", False))
    elif sw["case"] == "topple":
        per_row = p["per_rank"] * ranks // p["rows"] if weak else p["per_row"]
        if weak and (p["per_rank"] * ranks) % p["rows"]:
            raise ValueError(f"{sweep}: {p['per_rank']} x {ranks} dominoes do not fill {p['rows']} rows")
        scene, meta = domino_rows(per_row, p["rows"])
    elif sw["case"] == "slide":
        scene, meta = sliding_block(p["nx"], p["ny"], p["cells"])
    else:
        raise ValueError(sw["case"])
    if variant:
        if variant not in VARIANTS:
            raise KeyError(f"unknown variant '{variant}' (known: {', '.join(VARIANTS)})")
        if VARIANTS[variant]:
            scene["parallel"] = dict(VARIANTS[variant])
    scene["run"]["backend"] = backend
    scene["name"] = f"{sweep}_n{ranks}" + (f"_{variant}" if variant else "")
    meta.update({"sweep": sweep, "case": sw["case"], "mode": sw["mode"], "ranks": ranks, "preset": backend,
                 "preset_params": p, "variant": variant, "items": meta["n_vertices"] + meta["n_particles"],
                 "steps": p.get("steps"), "end_time": p.get("end_time"), "params": dict(params or {})})
    return scene, meta


def dump(scene: dict) -> str:
    if yaml is None:
        return json.dumps(scene, indent=1) + "\n"
    return yaml.safe_dump(scene, default_flow_style=None, sort_keys=False, width=160)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweep", nargs="?")
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--variant", default=None)
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args(argv)
    if a.list or not a.sweep:
        for name, sw in SWEEPS.items():
            for be in sw["presets"]:
                rows = []
                for n in sw["ranks"]:
                    _, m = scene_for(name, n, be)
                    rows.append(f"{n}:{m['n_tets'] / 1e3:.0f}k tets/{m['n_particles'] / 1e3:.0f}k p")
                print(f"{name:18s} {be:5s} {sw['mode']:6s} " + "  ".join(rows))
        return
    scene, meta = scene_for(a.sweep, a.ranks, a.backend, a.variant)
    sys.stdout.write(f"# {a.sweep} at {a.ranks} ranks, {a.backend} preset: {meta['n_tets']} tets, "
                     f"{meta['n_particles']} particles (generated by scaling/scenes.py)\n" + dump(scene))


if __name__ == "__main__":
    main()
