"""Hard case: failure paths of `qdemsph run`.

1. Run-time guard: a cube crushed by a prescribed velocity inverts a tet. Expected: exit code
   4, summary.json with status "failed" and the error text (naming the tet, body, step and
   time), and a final field snapshot at the failing step.
2. Output folder not writable (its parent is a regular file; also a folder under /proc):
   exit code 2 and a message naming the folder, before any step."""
import json
import subprocess
from pathlib import Path

import h5py
import numpy as np

HERE = Path(__file__).resolve().parent


def run_cli(qdemsph, scene, out, *sets):
    cmd = [str(qdemsph.binary), "run", str(scene), "--out", str(out), "--quiet", "--set", "run.threads=1"]
    for s in sets:
        cmd += ["--set", s]
    return cmd, subprocess.run(cmd, capture_output=True, text=True, timeout=600)


def test_simulation_error_writes_failed_summary_and_snapshot(qdemsph, checks, case_out):
    out = case_out / "run"
    cmd, proc = run_cli(qdemsph, HERE / "scene_crush.yaml", out)
    (case_out / "harness.log").write_text(f"$ {' '.join(cmd)}\n{proc.stdout}\n{proc.stderr}")
    checks.check("exit_code", proc.returncode, kind="abs", reference=4, tolerance=0, unit="-",
                 note=proc.stderr.strip()[:300])
    checks.check("stderr_names_inverted_tet", 1.0 if "inverted" in proc.stderr and "body 'cube'" in proc.stderr
                 else 0.0, kind="min", tolerance=1.0, unit="bool", note=proc.stderr.strip()[:300])
    s = json.loads((out / "summary.json").read_text()) if (out / "summary.json").exists() else {}
    checks.check("summary_status_failed", 1.0 if s.get("status") == "failed" else 0.0, kind="min",
                 tolerance=1.0, unit="bool", note=f"status={s.get('status')}")
    err = s.get("error", "")
    checks.check("summary_error_text", 1.0 if ("inverted" in err and "step " in err and "t = " in err) else 0.0,
                 kind="min", tolerance=1.0, unit="bool", note=err[:300])
    steps, t_fail = s.get("steps", -1), s.get("sim_time", np.nan)
    last_step, last_t, t, uz = -2, np.nan, [], []
    if (out / "fields.h5").exists():
        with h5py.File(out / "fields.h5", "r") as f:
            keys = sorted(f["steps"].keys())
            last = f["steps"][keys[-1]]
            last_step, last_t = int(last.attrs["step"]), float(last.attrs["time"])
            for k in keys:
                t.append(float(f["steps"][k].attrs["time"]))
                uz.append(float(np.min(f["steps"][k]["displacement"][:, 2])))
    checks.check("final_snapshot_at_failing_step", last_step, kind="abs", reference=steps, tolerance=0,
                 unit="step", note=f"last snapshot t = {last_t}, failure t = {t_fail}")
    checks.check("failure_time_before_full_crush", t_fail, kind="range", tolerance=[1e-4, 0.01], unit="s",
                 note="the top reaches the clamp at t = 0.01 s; a tet must invert before")
    checks.series("hard_guards", "min uz (snapshots up to the failure)", t, uz, style="line",
                  title="Crushed cube: run stops at the first inverted tet", xlabel="t (s)", ylabel="min uz (m)")
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
