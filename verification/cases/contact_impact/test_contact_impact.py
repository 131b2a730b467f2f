"""High-speed impact (issue 4): a 0.05 m cube at 20 m/s (tilted, spinning) into a fixed thick
block and into a thin plate (one element thick). No tunnelling: the cube rebounds, its centre
never crosses the struck surface and the overlap stays bounded. See README.md."""
from pathlib import Path

import numpy as np
import pytest

from harness import must

HERE = Path(__file__).resolve().parent
PLATE = "bodies.1.mesh={type: box, origin: [0, 0, -0.008], size: [0.15, 0.15, 0.008], cells: [6, 6, 1]}"


@pytest.mark.parametrize("target", ["block", "plate"])
def test_no_tunnelling(target, qdemsph, checks, case_out):
    sets = [PLATE] if target == "plate" else []
    run = must(qdemsph.run, HERE / "scene.yaml", case_out / "run", sets=sets)
    p = run.probes()
    t, z = p["time"], p["cube_z"]
    vz_end = float(np.polyfit(t[-20:], z[-20:], 1)[0])
    c = run.summary.get("contact", {})
    m = f"{target}."
    checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0, unit="bool")
    checks.check(m + "min_centre_height", float(z.min()), kind="min", tolerance=0.0, unit="m",
                 note="the struck surface is z = 0; a tunnelled cube ends below it")
    checks.check(m + "rebound_vz", vz_end, kind="min", tolerance=1.0, unit="m/s",
                 note="impact at -20 m/s; the cube must come back up")
    checks.check(m + "max_overlap", c.get("max_overlap_ever", np.nan), kind="max", tolerance=0.005,
                 unit="m", note="bounded penetration: below 5 D_DEM (D_DEM = 1 mm)")
    checks.info(m + "wall", run.solver_wall_s, unit="s", wall_s=run.solver_wall_s)
    checks.series("contact_impact", f"{target}", t, z, style="line", title="20 m/s impact: cube centre height",
                  xlabel="t (s)", ylabel="z (m)")
    checks.require()
