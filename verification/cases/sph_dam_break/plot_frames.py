#!/usr/bin/env python3
"""Pictures of an SPH run: fluid particles (x, y; coloured by pressure) at up to six snapshot
times, walls in grey.  /usr/bin/python3 plot_frames.py OUT_DIR [PNG]"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from harness.sph import fluid_frames  # noqa: E402


def main():
    out = Path(sys.argv[1])
    png = Path(sys.argv[2]) if len(sys.argv) > 2 else out / "fluid_frames.png"
    frames = fluid_frames(out, most=6)
    cols = 3 if len(frames) > 3 else len(frames)
    rows = int(np.ceil(len(frames) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 3.2 * rows), squeeze=False)
    pmax = max(np.percentile(f["p"][f["type"] == 0], 99) for f in frames)
    for ax, f in zip(axes.flat, frames):
        fl, w = f["type"] == 0, f["type"] == 1
        zw = f["x"][w, 2]
        back = w & (f["x"][:, 2] <= np.percentile(zw, 30))  # one z layer of the walls, not all
        ax.scatter(f["x"][back, 0], f["x"][back, 1], s=1, c="0.75", lw=0)
        sc = ax.scatter(f["x"][fl, 0], f["x"][fl, 1], s=2, c=f["p"][fl], cmap="viridis", vmin=0, vmax=pmax, lw=0)
        ax.set_title(f"t = {f['time']:.3f} s")
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    for ax in list(axes.flat)[len(frames):]:
        ax.axis("off")
    fig.colorbar(sc, ax=axes, label="pressure (Pa)", shrink=0.8)
    fig.savefig(png, dpi=110)
    print(png)


if __name__ == "__main__":
    main()
