"""Hard case: failure paths of `qdemsph run`.

1. Run-time guards, each on a scene made to trip it: a cube crushed fast by a prescribed
   velocity (20 m/s: a tet inverts within the first check interval), the same cube crushed at 0.5 m/s
   (its top tets get thinner until the step exceeds their stability limit, before any inverts), a
   cube sinking into a block through a far too soft contact (penetration bound), a block of
   water falling faster than its sound speed allows (fluid step limit). Expected for each:
   exit code 4, the guard's message naming the element / bodies / particle, step and time on
   stderr and in summary.json (status "failed"), and a final field snapshot at the failing
   step.
2. Output folder not writable (its parent is a regular file; also a folder under /proc):
   exit code 2 and a message naming the folder, before any step."""
import json
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

HERE = Path(__file__).resolve().parent

# name: (scene, overrides, words the message must contain, figure of the snapshots' min z
# displacement (solids) or min fluid height, (t_min, t_max) of the failure and why)
GUARDS = {
    "inverted_tet": ("scene_crush.yaml", ["constraints.1.velocity=[0,0,-20.0]"],
                     ["inverted", "body 'cube'"], (1e-4, 0.005),
                     "20 m/s: the top reaches the clamp at t = 5 ms; a tet inverts (top past the "
                     "middle nodes, 2.5 ms) before the first check (step 10, 3.4 ms) can see thin tets"),
    "stability_limit": ("scene_crush.yaml", ["constraints.1.velocity=[0,0,-0.5]", "run.end_time=0.1"],
                        ["exceeds the stability limit", "of tet", "body 'cube'"], (0.035, 0.08),
                        "0.5 m/s: the limit (checked every 100 steps, 34 ms) falls below dt = 0.5 x the "
                        "initial one after the first check and before the top has moved 40 mm (80 ms; at "
                        "0.3 m/s a tet inverts after 29 mm)"),
    "penetration": ("scene_penetration.yaml", [],
                    ["contact.max_penetration", "body 'cube' and body 'block'", "vertex"], (4e-4, 0.02),
                    "5 m/s: the surfaces meet at 0.4 ms (2 mm gap); the bound (12.5 mm) is crossed "
                    "before the cube has sunk 0.1 m (20 ms)"),
    "fluid_dt": ("scene_fluid_fall.yaml", [], ["fluid step", "SPH particle"], (0.25, 0.46),
                 "free fall passes 2 (c0 + sqrt(2 g H)) - c0 = 2.77 m/s at t = 0.28 s (the block "
                 "also spreads, so its fastest particle a little sooner); the limits are checked every "
                 "100 steps (0.17 s)"),
}


def run_cli(qdemsph, scene, out, *sets):
    cmd = [str(qdemsph.binary), "run", str(scene), "--out", str(out), "--quiet", "--set", "run.threads=1"]
    for s in sets:
        cmd += ["--set", s]
    return cmd, subprocess.run(cmd, capture_output=True, text=True, timeout=600)


def last_snapshot(path):
    """(step, time) of the last frame of a fields.h5 or fluid.h5, or (-2, nan)."""
    if not path.exists():
        return -2, np.nan
    with h5py.File(path, "r") as f:
        last = f["steps"][sorted(f["steps"].keys())[-1]]
        return int(last.attrs["step"]), float(last.attrs["time"])


@pytest.mark.parametrize("guard", list(GUARDS))
def test_guard_stops_with_message_summary_and_snapshot(qdemsph, checks, case_out, guard):
    scene, sets, words, (t_lo, t_hi), why = GUARDS[guard]
    out = case_out / "run"
    cmd, proc = run_cli(qdemsph, HERE / scene, out, *sets)
    (case_out / "harness.log").write_text(f"$ {' '.join(cmd)}\n{proc.stdout}\n{proc.stderr}")
    checks.check(f"{guard}.exit_code", proc.returncode, kind="abs", reference=4, tolerance=0, unit="-",
                 note=proc.stderr.strip()[:300])
    checks.check(f"{guard}.stderr_names_it", 1.0 if all(w in proc.stderr for w in words) else 0.0,
                 kind="min", tolerance=1.0, unit="bool", note=proc.stderr.strip()[:300])
    s = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    checks.check(f"{guard}.summary_status_failed", 1.0 if s.get("status") == "failed" else 0.0, kind="min",
                 tolerance=1.0, unit="bool", note=f"status={s.get('status')}")
    err = s.get("error", "")
    ok = all(w in err for w in words) and "step " in err and "t = " in err
    checks.check(f"{guard}.summary_error_text", 1.0 if ok else 0.0, kind="min", tolerance=1.0, unit="bool",
                 note=err[:300])
    steps, t_fail = s.get("steps", -1), s.get("sim_time", np.nan)
    snap = out / ("fluid.h5" if guard == "fluid_dt" else "fields.h5")
    last_step, last_t = last_snapshot(snap)
    checks.check(f"{guard}.final_snapshot_at_failing_step", last_step, kind="abs", reference=steps,
                 tolerance=0, unit="step", note=f"{snap.name}: last frame t = {last_t}, failure t = {t_fail}")
    checks.check(f"{guard}.failure_time", t_fail, kind="range", tolerance=[t_lo, t_hi], unit="s", note=why)
    if guard == "inverted_tet" or guard == "stability_limit":
        t, uz = [], []
        with h5py.File(out / "fields.h5", "r") as f:
            for k in sorted(f["steps"].keys()):
                t.append(float(f["steps"][k].attrs["time"]))
                uz.append(float(np.min(f["steps"][k]["displacement"][:, 2])))
        checks.series("hard_guards", f"{guard}: min uz (snapshots up to the failure)", t, uz, style="line",
                      title="Crushed cube: the run stops at the first guard", xlabel="t (s)",
                      ylabel="min uz (m)")
    checks.require()


def test_output_folder_not_writable(qdemsph, checks, case_out):
    blocker = case_out / "a_regular_file"
    blocker.write_text("not a folder\n")
    for label, out in (("parent_is_file", blocker / "out"), ("under_proc", Path("/proc/qdemsph_no_such/out"))):
        cmd, proc = run_cli(qdemsph, HERE / "scene_crush.yaml", out)
        (case_out / f"{label}.log").write_text(f"$ {' '.join(cmd)}\n{proc.stdout}\n{proc.stderr}")
        checks.check(f"{label}.exit_code", proc.returncode, kind="abs", reference=2, tolerance=0, unit="-",
                     note=proc.stderr.strip()[:300])
        ok = str(out) in proc.stderr and "output folder" in proc.stderr
        checks.check(f"{label}.message_names_folder", 1.0 if ok else 0.0, kind="min", tolerance=1.0,
                     unit="bool", note=proc.stderr.strip()[:300])
    checks.require()
