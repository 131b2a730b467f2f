"""A box leaning against a wall (the ladder problem): static friction at the floor and at the
wall together hold it up to the rigid-statics angle and no further. Each run releases the box
from rest at a tilt below or above the critical angle and checks that it stays put (its centre
drops less than HOLD_DROP after settling) or slides down (drops more than SLIDE_DROP). See
README.md."""
import math
from pathlib import Path

import numpy as np
import pytest

from harness import must

HERE = Path(__file__).resolve().parent
B, H, D_DEM = 0.0096, 0.032, 0.0004  # box thickness and height, contact diameter [m]
MU_A = 0.5                           # floor
HOLD_DROP = 1e-6                     # [m] centre drop from t = 0.02 s to the end: holding
SLIDE_DROP = 1e-3                    # [m] centre drop over the run: sliding


def holds(theta_deg, mu_b, mu_a=MU_A):
    """Rigid-body statics of the leaning box: True while friction can hold it."""
    t = math.radians(theta_deg)
    x_g = (H * math.sin(t) - B * math.cos(t)) / 2
    return x_g <= mu_a * (H * math.cos(t) + mu_b * H * math.sin(t)) / (1 + mu_a * mu_b)


def critical_angle(mu_b):
    lo, hi = 0.0, 89.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if holds(mid, mu_b) else (lo, mid)
    return lo


def placement(theta_deg, block):
    """Overrides putting the foot and the top edge D_DEM from floor and wall at this tilt."""
    t = math.radians(theta_deg)
    x_wall = B * math.cos(t) + H * math.sin(t) + D_DEM
    sets = [f"bodies.0.mesh.rotate.angle={theta_deg}",
            f"bodies.0.mesh.origin=[0, 0, {D_DEM + B * math.sin(t):.10f}]"]
    sets.append(f"bodies.1.mesh.origin=[{x_wall:.10f}, -0.01, 0]" if block
                else f"walls.1.point=[{x_wall:.10f}, 0, 0]")
    return sets


def run_ladder(qdemsph, case_out, wall, mu_b, theta):
    block = wall == "block"
    mu_key = "contact.mu" if block else "walls.1.mu"
    scene = HERE / ("scene_block.yaml" if block else "scene.yaml")
    run = must(qdemsph.run, scene, case_out / f"{wall}_mu{mu_b}_{theta}",
               sets=placement(theta, block) + [f"{mu_key}={mu_b}"])
    p = run.probes()
    return run, p["time"], p["box_z"]


# (wall, mu_B, tilt below the critical angle, tilt above it); quick tier: the analytic wall.
CASES = [("plane", 0.5, 59.0, 63.0), ("plane", 0.0, 50.0, 54.0)]
FULL_CASES = [("block", 0.5, 58.0, 63.0), ("plane", 0.3, 55.0, 59.0)]


def check_case(qdemsph, checks, case_out, wall, mu_b, below, above):
    crit = critical_angle(mu_b)
    assert below < crit < above, "the case must bracket the statics angle"
    m = f"{wall}.muB{mu_b}."
    checks.info(m + "critical_angle", crit, unit="deg",
                note=f"rigid statics, mu_A {MU_A}, mu_B {mu_b}, b/h = {B / H:.2f}")
    meta = dict(title="Leaning box: centre height", xlabel="t (s)", ylabel="z - z0 (m)")
    run, t, z = run_ladder(qdemsph, case_out, wall, mu_b, below)
    settled = t >= 0.02
    checks.check(m + f"hold_{below:g}deg.drop", float(z[settled][0] - z[-1]), kind="max",
                 tolerance=HOLD_DROP, unit="m", wall_s=run.solver_wall_s,
                 note=f"{crit - below:.1f} deg below the critical angle: must hold")
    checks.series("contact_ladder", f"{wall} mu_B={mu_b} {below:g} deg (holds)", t, z - z[0],
                  style="line", **meta)
    run, t, z = run_ladder(qdemsph, case_out, wall, mu_b, above)
    checks.check(m + f"slide_{above:g}deg.drop", float(z[0] - z[-1]), kind="min",
                 tolerance=SLIDE_DROP, unit="m", wall_s=run.solver_wall_s,
                 note=f"{above - crit:.1f} deg above the critical angle: must slide")
    checks.series("contact_ladder", f"{wall} mu_B={mu_b} {above:g} deg (slides)", t, z - z[0],
                  style="line", **meta)
    checks.require()


@pytest.mark.parametrize("wall,mu_b,below,above", CASES)
def test_holds_below_and_slides_above_the_statics_angle(wall, mu_b, below, above, qdemsph,
                                                        checks, case_out):
    check_case(qdemsph, checks, case_out, wall, mu_b, below, above)


@pytest.mark.full
@pytest.mark.parametrize("wall,mu_b,below,above", FULL_CASES)
def test_full_block_wall_and_mu_03(wall, mu_b, below, above, qdemsph, checks, case_out):
    check_case(qdemsph, checks, case_out, wall, mu_b, below, above)
