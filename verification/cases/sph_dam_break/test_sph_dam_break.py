"""Dam break (BENCHMARKS.md section 6): surge front against Martin & Moyce 1952 and the water
level at x = 0.300 m against Lobovsky et al. 2014, at two resolutions each (the finer ones in
the long tier). See README.md for the release-time shift and the tolerances."""
from pathlib import Path

import numpy as np
import pytest

from harness import must
from harness.sph import fluid_csv, fluid_frames, rms, water_level

HERE = Path(__file__).resolve().parent
G = 9.81

# Martin & Moyce 1952, a = 2.25 in, column a wide x 2a high: Z = x_front / a, T = t sqrt(2 g / a).
MM_A = 0.05715
MM_T = np.array([0.00, 0.41, 0.84, 1.19, 1.43, 1.63, 1.82, 1.97, 2.20, 2.32, 2.50, 2.64, 2.82, 2.96])
MM_Z = np.array([1.00, 1.11, 1.23, 1.44, 1.67, 1.89, 2.11, 2.33, 2.56, 2.78, 3.00, 3.22, 3.44, 3.67])
MM_SHIFT = 0.175  # added to the simulated T: the experiment's gate needs time to open
# Lobovsky et al. 2014, H = 0.3 m, gauge x = 0.300 m: h / H at T = t sqrt(g / H).
LB_H, LB_X = 0.3, 0.300
LB_TANK = (np.array([0.0, 0.0, 0.0]), np.array([1.61, 0.60, 0.08]))  # inner box, open top
LB_T = np.array([0, 1, 2, 3, 4, 5, 6], dtype=float)
LB_h = np.array([1.000, 0.931, 0.783, 0.632, 0.500, 0.402, 0.325])

MM_RES = {"a10": (MM_A / 10, "quick"), "a15": (MM_A / 15, "full"), "a20": (MM_A / 20, "full")}
LB_RES = {"H15": (LB_H / 15, "full"), "H30": (LB_H / 30, "full")}


def _tier_mark(tier):
    return [pytest.mark.full] if tier == "full" else []


@pytest.mark.parametrize("res", [pytest.param(k, marks=_tier_mark(v[1])) for k, v in MM_RES.items()])
def test_martin_moyce_front(res, qdemsph, checks, case_out):
    dx = MM_RES[res][0]
    run = must(qdemsph.run, HERE / "scene_mm.yaml", case_out / "run", sets=[f"fluid.spacing={dx!r}"])
    checks.check(f"{res}.completed", 1.0 if run.status == "completed" else 0.0, kind="min",
                 tolerance=1.0, unit="bool", backend=run.backend)
    c = must(fluid_csv, run.out)
    Ts = c["time"] * np.sqrt(2 * G / MM_A)
    Zs = (c["x_max"] + 0.5 * dx) / MM_A
    m = MM_T > 0
    z_shift = np.interp(MM_T, Ts + MM_SHIFT, Zs)
    z_raw = np.interp(MM_T, Ts, Zs)
    checks.check(f"{res}.front_rms_error", rms(z_shift[m] - MM_Z[m]), kind="max", tolerance=0.15,
                 unit="a", wall_s=run.solver_wall_s, backend=run.backend,
                 note=f"simulated T + {MM_SHIFT} (gate release); Z = (x_max + dx/2) / a")
    checks.info(f"{res}.front_rms_error_unshifted", rms(z_raw[m] - MM_Z[m]), unit="a")
    checks.info(f"{res}.front_max_error", float(np.abs(z_shift[m] - MM_Z[m]).max()), unit="a")
    checks.info(f"{res}.particle_steps_per_s", run.summary.get("fluid", {}).get("particle_steps_per_s", 0.0),
                unit="1/s", backend=run.backend)
    fig = "sph_dam_break_martin_moyce"
    meta = dict(title="Dam break surge front (Martin & Moyce 1952)", xlabel="T = t sqrt(2g/a)", ylabel="Z = x/a")
    checks.series(fig, "Martin & Moyce 1952", MM_T, MM_Z, style="points", **meta)
    checks.series(fig, f"SPH dx = a/{round(MM_A / dx)} (T + {MM_SHIFT})", Ts + MM_SHIFT, Zs, style="line", **meta)
    checks.require()


@pytest.mark.parametrize("res", [pytest.param(k, marks=_tier_mark(v[1])) for k, v in LB_RES.items()])
def test_lobovsky_gauge(res, qdemsph, checks, case_out):
    dx = LB_RES[res][0]
    run = must(qdemsph.run, HERE / "scene_lobovsky.yaml", case_out / "run", sets=[f"fluid.spacing={dx!r}"])
    checks.check(f"{res}.completed", 1.0 if run.status == "completed" else 0.0, kind="min",
                 tolerance=1.0, unit="bool", backend=run.backend)
    frames = must(fluid_frames, run.out)
    t = np.array([f["time"] for f in frames])
    h = np.array([water_level(f, LB_X, dx) for f in frames])
    Ts, hs = t * np.sqrt(G / LB_H), h / LB_H
    hi = np.interp(LB_T, Ts, hs)
    checks.check(f"{res}.gauge_rms_error", rms(hi - LB_h), kind="max", tolerance=0.05, unit="H",
                 wall_s=run.solver_wall_s, backend=run.backend, note="water level h/H at x = 0.300 m, T = 0..6")
    # Wall penetration after the far-wall impact: depth of fluid particle centres past the tank's
    # inner surface (0.5 dx: the first wall layer; 3 dx: through the wall), splashes above the
    # open top excluded.
    depth_max, through, past = 0.0, 0, 0.0
    lo, hi_box = LB_TANK
    for f in frames:
        x = f["x"][(f["type"] == 0) & (f["x"][:, 1] <= hi_box[1])]
        d = np.maximum(lo - x, x - hi_box).max(axis=1) / dx
        depth_max = max(depth_max, float(d.max()))
        through = max(through, int((d > 3).sum()))
        past = max(past, float((d > 0).mean()))
    checks.check(f"{res}.particles_through_wall", through, kind="max", tolerance=0, unit="particles",
                 note="fluid centres beyond the 3 wall layers in any frame")
    checks.check(f"{res}.wall_penetration_max", depth_max, kind="max", tolerance=1.0, unit="dx",
                 note="deepest fluid centre past the tank's inner surface in any frame (first wall layer at 0.5 dx)")
    checks.info(f"{res}.fraction_past_wall_surface_max", past, unit="-",
                note="largest fraction of fluid centres past the inner surface in one frame")
    fig = "sph_dam_break_lobovsky"
    meta = dict(title="Dam break water level at x = 0.300 m (Lobovsky et al. 2014)", xlabel="T = t sqrt(g/H)", ylabel="h/H")
    checks.series(fig, "Lobovsky et al. 2014", LB_T, LB_h, style="points", **meta)
    checks.series(fig, f"SPH dx = H/{round(LB_H / dx)}", Ts, hs, style="line", **meta)
    checks.require()
