#!/usr/bin/python3
"""Pictures of one qdemsph run: probes.png (probe histories and the energy budget) and
snapshots.png (deformed shape coloured by von Mises stress at several times).

Usage: /usr/bin/python3 verification/tools/plot_run.py RUN_DIR
"""
import csv
import json
import sys
from pathlib import Path

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ENERGIES = ["kinetic", "strain", "potential", "dissipated", "contact", "contact_dissipated", "total"]


def title_of(run):
    """The scene's name from summary.json, else the folder's."""
    try:
        return json.loads((run / "summary.json").read_text())["name"]
    except (OSError, KeyError, ValueError):
        return run.name


def read_probes(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head, data = rows[0], np.array(rows[1:], dtype=float)
    return {h: data[:, i] for i, h in enumerate(head)}


def plot_probes(run, cols):
    names = sorted({c[:-2] for c in cols if c.endswith("_x")})
    fig, axes = plt.subplots(len(names) + 1, 1, figsize=(8, 2.6 * (len(names) + 1)), sharex=True)
    t = cols["time"]
    for ax, name in zip(axes, names):
        for comp in "xyz":
            ax.plot(t, cols[f"{name}_{comp}"], label=f"{name}_{comp}")
        ax.set_ylabel(f"{name} [m]")
        ax.legend(loc="upper right", fontsize=8)
        ax.grid(alpha=0.3)
    ax = axes[-1]
    for e in (e for e in ENERGIES if e in cols):  # older runs lack the contact columns
        ax.plot(t, cols[e], label=e, lw=2 if e == "total" else 1)
    ax.set_ylabel("energy [J]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="upper right", fontsize=8)
    ax.grid(alpha=0.3)
    fig.suptitle(title_of(run))
    fig.tight_layout()
    fig.savefig(run / "probes.png", dpi=110)
    plt.close(fig)


def plot_snapshots(run, frames=6):
    with h5py.File(run / "fields.h5", "r") as f:
        tets = f["/mesh/tets"][...]
        keys = sorted(f["/steps"].keys())
        pick = [keys[int(round(i))] for i in np.linspace(0, len(keys) - 1, min(frames, len(keys)))]
        snaps = []
        for k in pick:
            g = f["/steps"][k]
            x = g["position"][...]
            snaps.append((g.attrs["time"], x[tets].mean(axis=1), g["von_mises"][...]))
    vmax = max(s[2].max() for s in snaps) or 1.0
    # View along the axis in which the body is thinnest at rest.
    extent = np.ptp(snaps[0][1], axis=0)
    a, b = [i for i in range(3) if i != int(np.argmin(extent))]
    fig, axes = plt.subplots(len(snaps), 1, figsize=(8, 1.6 * len(snaps)), sharex=True, sharey=True)
    axes = np.atleast_1d(axes)
    for ax, (t, c, vm) in zip(axes, snaps):
        sc = ax.scatter(c[:, a], c[:, b], c=vm, s=6, cmap="viridis", vmin=0, vmax=vmax)
        ax.set_aspect("equal")
        ax.set_ylabel(f"t = {t:.3f} s", fontsize=8)
    axes[-1].set_xlabel("xyz"[a] + " [m]")
    fig.colorbar(sc, ax=list(axes), label="von Mises [Pa]")
    fig.suptitle(f"{title_of(run)}: tet centroids coloured by von Mises stress")
    fig.savefig(run / "snapshots.png", dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    run = Path(sys.argv[1])
    plot_probes(run, read_probes(run / "probes.csv"))
    plot_snapshots(run)
    print(f"wrote {run / 'probes.png'} and {run / 'snapshots.png'}")


if __name__ == "__main__":
    main()
