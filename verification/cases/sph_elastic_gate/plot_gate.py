#!/usr/bin/env python3
"""Pictures of an elastic-gate run: the particles near the gate (fluid coloured by pressure,
gate markers red, walls grey) at up to six snapshot times, and the gate's free-tip
displacement against the experiment.  /usr/bin/python3 plot_gate.py OUT_DIR [PNG]"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness.sph import fluid_frames  # noqa: E402
from test_sph_elastic_gate import EXP_T, EXP_X, EXP_Y  # noqa: E402


def main():
    out = Path(sys.argv[1])
    png = Path(sys.argv[2]) if len(sys.argv) > 2 else out / "gate_frames.png"
    frames = fluid_frames(out, most=6)
    fig = plt.figure(figsize=(15, 8.5))
    gs = fig.add_gridspec(3, 3)
    pmax = max(np.percentile(f["p"][f["type"] == 0], 99) for f in frames)
    sc = None
    for n, f in enumerate(frames):
        ax = fig.add_subplot(gs[n // 3, n % 3])
        x, typ = f["x"], f["type"]
        w = (typ == 1) & (x[:, 2] <= np.percentile(x[typ == 1, 2], 30))  # walls: one z side
        ax.scatter(x[w, 0], x[w, 1], s=1, c="0.8", lw=0)
        fl = typ == 0  # all z layers of the slab on top of each other
        sc = ax.scatter(x[fl, 0], x[fl, 1], s=3, c=f["p"][fl], cmap="viridis", vmin=0, vmax=pmax, lw=0)
        mk = typ == 2
        ax.scatter(x[mk, 0], x[mk, 1], s=3, c="tab:red", lw=0)
        ax.set_xlim(-0.01, 0.30)
        ax.set_ylim(-0.01, 0.16)
        ax.set_aspect("equal")
        ax.set_title(f"t = {f['time']:.3f} s", fontsize=10)
    if sc is not None:
        fig.colorbar(sc, ax=fig.axes, label="pressure (Pa)", shrink=0.6)
    ax = fig.add_subplot(gs[2, :2])
    p = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    ax.plot(p["time"], 1e3 * p["tip_x"], label="qdemsph horizontal")
    ax.plot(p["time"], 1e3 * p["tip_y"], label="qdemsph vertical (up)")
    ax.plot(EXP_T, EXP_X, "o", color="tab:blue", mfc="none", label="experiment horizontal")
    ax.plot(EXP_T, EXP_Y, "s", color="tab:orange", mfc="none", label="experiment vertical")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("tip displacement (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(png, dpi=100)
    print(png)


if __name__ == "__main__":
    main()
