#!/usr/bin/python3
"""Pictures of a coupled fluid-structure run (a scene with `fluid:` and bodies):

  frames.png  4-6 snapshots: fluid particles coloured by speed, the bodies' surface triangles
              coloured by von Mises stress, the tank floor/end walls/steps in grey; side view
              (or top view), the same window in every panel (spray leaving it is clipped).
  forces.png  time histories: the fluid's total force on the bodies (fluid.csv fbx, fby, fbz);
              the probes' displacement from t = 0 (probes.csv: `com` or `displacement` probes);
              the largest von Mises stress of each body (fields.h5 frames); energies (fluid
              kinetic from fluid.csv, the bodies' kinetic, strain, contact and dissipated).

Usage: /usr/bin/python3 verification/tools/plot_fsi.py RUN_DIR [--frames N] [--view side|top]
                                                               [--up x|y|z]
  --up: the vertical axis; by default the axis along which the fluid's centre of mass fell most
  between the first and the last frame (z when it did not fall).
Reads RUN_DIR/{fluid.h5, fields.h5, fluid.csv, probes.csv, summary.json} (docs/scene-format.md).
"""
import argparse
import json
import sys
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # verification/
from harness.sph import fluid_csv, fluid_frames  # noqa: E402
from tools.plot_run import read_probes, title_of  # noqa: E402

AXES = "xyz"
FLUID_CMAP = matplotlib.colors.LinearSegmentedColormap.from_list(
    "water", plt.get_cmap("Blues")(np.linspace(0.35, 1.0, 256)))
BODY_CMAP = "YlOrRd"


def surface_faces(tets):
    """Boundary triangles of a tet mesh (faces that belong to one tet) and their tet index."""
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    owner = np.tile(np.arange(len(tets)), 4)
    _, inv, count = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
    once = count[inv.ravel()] == 1
    return faces[once], owner[once]


def body_names(run, n):
    """Body names in the order of fields.h5's /mesh/body (free bodies first, fixed last, as
    build_model orders them), read from the scene named in summary.json; else 'body k'."""
    try:
        import yaml

        scene = yaml.safe_load(Path(json.loads((run / "summary.json").read_text())["scene"]).read_text())
        bodies = scene["bodies"]
        names = [b["name"] for b in bodies if not b.get("fixed")] + [b["name"] for b in bodies if b.get("fixed")]
        if len(names) == n:
            return names
    except Exception:  # noqa: BLE001 - labels only; fall back to numbers
        pass
    return [f"body {k}" for k in range(n)]


def choose_axes(first, last, up, view):
    """(horizontal, vertical, depth) axes of the picture. Side view: the up axis vertical, the
    horizontal axis the one along which the fluid spread most; top view: looking down."""
    fl0, fl1 = first["type"] == 0, last["type"] == 0
    if up is None:
        drop = last["x"][fl1].mean(axis=0) - first["x"][fl0].mean(axis=0)
        up = int(np.argmin(drop)) if drop.min() < 0 else 2
    others = [a for a in range(3) if a != up]
    spread = [np.ptp(np.concatenate([first["x"][fl0, a], last["x"][fl1, a]])) for a in others]
    h, d = (others[0], others[1]) if spread[0] >= spread[1] else (others[1], others[0])
    return (h, up, d) if view == "side" else (h, d, up)


def plot_frames(run, n_frames, up, view):
    frames = fluid_frames(run, most=n_frames)
    bodies = []
    with h5py.File(run / "fields.h5", "r") as fb:
        tets = fb["/mesh/tets"][...]
        vbody = fb["/mesh/body"][...]
        tri, owner = surface_faces(tets)
        steps = sorted(fb["/steps"].keys())
        times = np.array([fb["/steps"][k].attrs["time"] for k in steps])
        for fr in frames:  # the field frame at the fluid frame's time
            g = fb["/steps"][steps[int(np.argmin(np.abs(times - fr["time"])))]]
            bodies.append((g["position"][...], g["von_mises"][...]))
    names = body_names(run, int(vbody.max()) + 1 if len(vbody) else 0)

    a, b, d = choose_axes(frames[0], frames[-1], up, view)
    w0 = frames[0]["type"] == 1
    fl0 = frames[0]["type"] == 0
    dx = np.median(np.diff(np.unique(np.round(frames[0]["x"][fl0, a], 9)))) if fl0.sum() > 1 else 0.01
    # Walls to draw: those within the fluid's depth range (floor, end walls, slopes), not the
    # side walls in front of and behind the flow, which would cover everything.
    lo, hi = frames[0]["x"][fl0, d].min() - 0.25 * dx, frames[0]["x"][fl0, d].max() + 0.25 * dx
    if view == "top":  # looking down: the floor would cover everything; draw what stands up
        lo, hi = frames[0]["x"][fl0, d].min() + 0.25 * dx, np.inf
    wall = w0 & (frames[0]["x"][:, d] >= lo) & (frames[0]["x"][:, d] <= hi)
    wx = frames[0]["x"][wall]
    # One window for all panels: the drawn walls, the bodies and the fluid at the start (spray
    # that leaves the tank is clipped), with room above for the run-up.
    pts = np.concatenate([wx[:, [a, b]], frames[0]["x"][fl0][:, [a, b]]] + [x[:, [a, b]] for x, _ in bodies])
    pad = 2 * dx
    x0, x1 = pts[:, 0].min() - pad, pts[:, 0].max() + pad
    y0, y1 = pts[:, 1].min() - pad, pts[:, 1].max() + pad
    if view == "side":
        y1 += 0.15 * (x1 - x0)
    vmax = max(np.percentile(np.linalg.norm(f["v"][f["type"] == 0], axis=1), 99.5) for f in frames) or 1.0
    # Stress on a square-root scale up to the 99th percentile of the drawn frames' tets (a contact
    # hot spot would wash out the rest): the resting weight (~rho g h) stays visible.
    allvm = np.concatenate([vm for _, vm in bodies])
    smax = float(np.percentile(allvm, 99)) if len(allvm) else 1.0
    smax = smax or 1.0
    snorm = matplotlib.colors.PowerNorm(gamma=0.5, vmin=0.0, vmax=smax)

    cols = 2 if len(frames) <= 4 else 3
    rows = int(np.ceil(len(frames) / cols))
    pw = 4.6  # panel width [in]
    ph = (pw - 0.4) * (y1 - y0) / (x1 - x0) + 0.3  # panel height with its title
    fig, axes = plt.subplots(rows, cols, figsize=(pw * cols + 2.2, rows * ph + 0.9),
                             squeeze=False, sharex=True, sharey=True, layout="constrained")
    ms = max(0.3, min(6.0, 4000.0 / max(1, fl0.sum()) ** 0.75))  # marker size by particle count
    for ax, fr, (xb, vm) in zip(axes.flat, frames, bodies):
        ax.scatter(wx[:, a], wx[:, b], s=ms, c="0.6", lw=0, rasterized=True)
        fl = fr["type"] == 0
        xf, sp = fr["x"][fl], np.linalg.norm(fr["v"][fl], axis=1)
        order = np.argsort(-xf[:, d] if view == "side" else xf[:, d])  # far first, near last
        sc = ax.scatter(xf[order, a], xf[order, b], s=ms, c=sp[order], cmap=FLUID_CMAP, vmin=0, vmax=vmax,
                        lw=0, rasterized=True)
        pc = None
        if len(tri):
            poly = xb[tri][:, :, [a, b]]
            depth = xb[tri][:, :, d].mean(axis=1)
            o = np.argsort(-depth if view == "side" else depth)
            pc = PolyCollection(poly[o], array=vm[owner[o]], cmap=BODY_CMAP, norm=snorm,
                                edgecolors="0.15", linewidths=0.3, zorder=3)
            ax.add_collection(pc)
            for k, name in enumerate(names if fr is frames[0] else []):  # names on the first panel
                xs = xb[vbody == k]
                if len(xs):
                    ax.annotate(name, (xs[:, a].mean(), xs[:, b].max()), xytext=(0, 3 + 9 * (k % 2)),
                                textcoords="offset points", ha="center", fontsize=7, zorder=4)
        ax.set_title(f"t = {fr['time']:.3f} s", fontsize=10)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
    for ax in axes[-1]:
        ax.set_xlabel(f"{AXES[a]} [m]")
    for ax in axes[:, 0]:
        ax.set_ylabel(f"{AXES[b]} [m]")
    for ax in list(axes.flat)[len(frames):]:
        ax.axis("off")
    fig.colorbar(sc, ax=axes, label="fluid speed [m/s]", shrink=0.9, aspect=30)
    if pc is not None:
        fig.colorbar(pc, ax=axes, label="body von Mises [Pa]", shrink=0.9, aspect=30, extend="max")
    what = "side view" if view == "side" else "top view"
    fig.suptitle(f"{title_of(run)}: fluid by speed, bodies by von Mises stress ({what}, looking along "
                 f"{'+' if view == 'side' else '-'}{AXES[d]})")
    fig.savefig(run / "frames.png", dpi=110)
    plt.close(fig)
    return names


def running_mean(y, n):
    """Centred n-sample mean, the ends padded with the end values (not zeros)."""
    if n <= 1 or len(y) < 2:
        return y
    yp = np.concatenate([np.full(n // 2, y[0]), y, np.full(n - 1 - n // 2, y[-1])])
    return np.convolve(yp, np.ones(n) / n, mode="valid")


def peak_stress(run):
    """Times of fields.h5 frames and the largest von Mises stress of each body at each."""
    with h5py.File(run / "fields.h5", "r") as fb:
        tets = fb["/mesh/tets"][...]
        tbody = fb["/mesh/body"][...][tets[:, 0]]
        steps = sorted(fb["/steps"].keys())
        t = np.array([fb["/steps"][k].attrs["time"] for k in steps])
        nb = int(tbody.max()) + 1 if len(tbody) else 0
        peak = np.array([[fb["/steps"][k]["von_mises"][...][tbody == j].max() for j in range(nb)] for k in steps])
    return t, peak.reshape(len(steps), nb)


def plot_forces(run, names):
    fc = fluid_csv(run)
    pr = read_probes(run / "probes.csv")
    ts, peak = peak_stress(run)
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharex=True)
    ax = axes[0, 0]
    t = fc["time"]
    n = max(1, int(round(0.02 / np.median(np.diff(t))))) if len(t) > 2 else 1  # 20 ms mean
    for i, c in enumerate(("fbx", "fby", "fbz")):
        ax.plot(t, fc[c], color=f"C{i}", lw=0.6, alpha=0.35)
        ax.plot(t, running_mean(fc[c], n), color=f"C{i}", lw=1.5, label=c)
    ax.set_title("thin: every sample; thick: 20 ms running mean", fontsize=9)
    ax.set_ylabel("fluid force on the bodies [N]")
    ax.legend(fontsize=8)

    ax = axes[0, 1]
    probes = [c[:-2] for c in pr if c.endswith("_x")]  # scene order
    tp = pr["time"]
    n = max(1, int(round(0.02 / np.median(np.diff(tp))))) if len(tp) > 2 else 1
    for i, p in enumerate(probes):
        col = f"C{i}"
        for comp, ls in zip("xyz", ("-", "--", ":")):
            u = pr[f"{p}_{comp}"] - pr[f"{p}_{comp}"][0]
            ax.plot(tp, u, ls, color=col, lw=0.5, alpha=0.3)
            ax.plot(tp, running_mean(u, n), ls, color=col, lw=1.3, label=f"{p} {comp}")
    ax.set_ylabel("probe displacement from t = 0 [m]")
    if probes:
        ax.legend(fontsize=7, ncol=max(1, len(probes)))
    else:
        ax.text(0.5, 0.5, "no probes in the scene", transform=ax.transAxes, ha="center")

    ax = axes[1, 0]
    for j in range(peak.shape[1]):
        ax.plot(ts, peak[:, j], "o-", ms=3, label=names[j] if j < len(names) else f"body {j}")
    if peak.shape[1]:
        ax.legend(fontsize=8)
    ax.set_yscale("log")
    if peak.size and peak.max() > 0:
        ax.set_ylim(bottom=peak.max() * 1e-4)  # the unloaded start is ~0
    ax.set_ylabel("largest von Mises stress [Pa]")

    ax = axes[1, 1]
    floor = 1e-9
    ax.plot(fc["time"], np.maximum(fc["kinetic"], floor), label="fluid kinetic")
    for e in ("kinetic", "strain", "contact", "contact_dissipated", "dissipated"):
        if e in pr and np.any(pr[e] > 0):
            ax.plot(pr["time"], np.maximum(pr[e], floor), label=f"bodies {e}", lw=1)
    ax.set_yscale("log")
    ax.set_ylabel("energy [J]")
    ax.legend(fontsize=7)
    ax.set_title(f"largest |rho/rho0 - 1| of the fluid: {fc['rho_dev'].max():.3f}", fontsize=9)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(title_of(run))
    fig.tight_layout()
    fig.savefig(run / "forces.png", dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", type=Path)
    ap.add_argument("--frames", type=int, default=6)
    ap.add_argument("--view", choices=("side", "top"), default="side")
    ap.add_argument("--up", choices=tuple(AXES))
    args = ap.parse_args()
    up = AXES.index(args.up) if args.up else None
    names = plot_frames(args.run, max(1, args.frames), up, args.view)
    plot_forces(args.run, names)
    print(f"wrote {args.run / 'frames.png'} and {args.run / 'forces.png'}")


if __name__ == "__main__":
    main()
