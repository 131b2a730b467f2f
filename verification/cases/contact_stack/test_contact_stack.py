"""Stacked cubes settling under gravity on a plane (issue 4; the report's Fig. 7 stack).
Quick tier: 2x2x2 cubes of 768 tets for 0.4 s. Long tier: the report's 3x3x3 stack of
6,144-tet cubes for 1 s. Checks: the run completes, kinetic energy decays from its peak, the
cubes do not drift sideways by D_DEM, no interpenetration beyond D_DEM. See README.md."""
import sys
from pathlib import Path

import numpy as np
import pytest

from harness import must

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from stack_metrics import D_DEM, stack_metrics  # noqa: E402


def check_stack(run, checks, m, t_window):
    p = run.probes()
    t, ke = p["time"], p["kinetic"]
    s = stack_metrics(p, run.summary, t_window)
    checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0, unit="bool")
    checks.check(m + "ke_end_over_peak", s["ke_end_over_peak"], kind="max", tolerance=0.5, unit="-",
                 note="kinetic energy decays after the stack lands")
    checks.check(m + "lateral_drift", s["lateral_drift"], kind="max", tolerance=D_DEM, unit="m",
                 note=f"peak-to-peak x, y of every cube centre over the last {t_window} s")
    checks.check(m + "max_overlap", s["max_overlap"], kind="max", tolerance=2 * D_DEM, unit="m",
                 note="D_DEM - gap: 2 D_DEM means the surfaces themselves meet")
    checks.info(m + "vertical_settlement", s["vertical_settlement"], unit="m")
    checks.info(m + "wall", run.solver_wall_s, unit="s", wall_s=run.solver_wall_s)
    for k, v in run.summary.get("phases", {}).items():
        if k.startswith("contact") or k in ("elements", "integration"):
            checks.info(m + f"phase.{k}_per_step", v / max(run.summary.get("steps", 1), 1), unit="s",
                        wall_s=run.solver_wall_s)
    checks.series(f"contact_stack_{m[:-1]}", "kinetic energy", t, ke, style="line",
                  title=f"Stack ({m[:-1]}): kinetic energy", xlabel="t (s)", ylabel="KE (J)")
    checks.require()


def test_stack_8_quick(qdemsph, checks, case_out):
    run = must(qdemsph.run, HERE / "scene_8.yaml", case_out / "run")
    check_stack(run, checks, "stack8.", 0.2)


@pytest.mark.full
def test_stack_27_report(qdemsph, checks, case_out):
    run = must(qdemsph.run, HERE / "scene_27.yaml", case_out / "run")
    check_stack(run, checks, "stack27.", 0.5)


@pytest.mark.parametrize("size", ["small", pytest.param("report", marks=pytest.mark.full)])
def test_broad_phase_modes_fig7(size, qdemsph, checks, case_out):
    """The report's Fig. 7 on the stack: (A) all tets, (B) surface tets, (C) surface polygons in
    the cell list. The physics must not depend on the mode (same contacts); the time per step of
    each phase is recorded (timings are shown, never failed). The JSON record is written by
    verification/bench/contact_modes.py; this test records the same numbers in the report."""
    scene = HERE / ("scene_8.yaml" if size == "small" else "scene_27.yaml")
    steps, dt = (30, 1.5e-4) if size == "small" else (20, 1.5e-4)
    res = {}
    for key, mode in (("A", "all_tets"), ("B", "surface_tets"), ("C", "polygons")):
        run = must(qdemsph.run, scene, case_out / mode,
                   sets=[f"contact.broad_phase={mode}", "contact.skin=0", f"run.dt={dt}", f"run.end_time={steps * dt * (1 - 1e-6)}",
                         f"output.probes_every={steps * dt}"])
        res[key] = run
        n = max(run.summary.get("steps", 1), 1)
        for ph in ("contact", "contact.broad", "contact.narrow", "contact.force", "elements"):
            checks.info(f"{size}.{key}.{ph}_per_step", run.summary["phases"].get(ph, 0) / n, unit="s",
                        wall_s=run.solver_wall_s)
        checks.info(f"{size}.{key}.candidate_pairs", run.summary["contact"]["pairs"], unit="pairs")
    ref = res["C"].summary["contact"]["contacts"]
    for key in ("A", "B"):
        checks.check(f"{size}.{key}.same_contacts_as_C", res[key].summary["contact"]["contacts"], kind="abs",
                     reference=ref, tolerance=0, unit="contacts", note="the broad phase must not change the physics")
    c = res["C"].summary["phases"].get("contact", 0)
    for key in ("A", "B"):
        checks.info(f"{size}.{key}_over_C.contact", res[key].summary["phases"].get("contact", 0) / c if c else np.nan, unit="-")
    xs, labels = [0, 1, 2], ["A all tets", "B surface tets", "C polygons"]
    for ph in ("contact.broad", "contact.narrow", "contact.force"):
        checks.series(f"contact_fig7_{size}", ph, xs,
                      [res[k].summary["phases"].get(ph, 0) / max(res[k].summary["steps"], 1) for k in "ABC"],
                      style="points", title=f"Fig. 7 ({size} stack): seconds per step by phase",
                      xlabel="0: A all tets, 1: B surface tets, 2: C polygons", ylabel="s / step", yscale="log")
    checks.require()
