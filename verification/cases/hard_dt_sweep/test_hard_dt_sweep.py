"""Hard case: dt swept up to the stability limit. dt_safety 0.5 ... 0.99 x the limit: the run
completes and the Verlet energy stays bounded. run.dt = 1.5 and 3 x the limit: the solver
must refuse the run before stepping (exit code 2, a message naming the limit and the tet that
sets it). See README.md."""
import subprocess
from pathlib import Path

import numpy as np

from harness import must

HERE = Path(__file__).resolve().parent
STABLE = (0.5, 0.7, 0.9, 0.95, 0.99)
UNSTABLE = (1.5, 3.0)


def test_dt_sweep(qdemsph, checks, case_out):
    devs, crit = [], None
    for f in STABLE:
        run = must(qdemsph.run, HERE / "scene.yaml", case_out / f"safety_{f}", sets=[f"run.dt_safety={f}"])
        crit = float(run.summary["dt_critical"])
        checks.check(f"x{f}.completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0,
                     unit="bool", note=f"status={run.status} {run.summary.get('error', '')}")
        checks.check(f"x{f}.dt_over_limit", float(run.summary["dt"]) / crit, kind="rel", reference=f,
                     tolerance=1e-12, unit="-")
        e = run.probes()["total"]
        dev = float(np.max(np.abs(e - e[0])) / e[0])
        devs.append(dev)
        checks.check(f"x{f}.energy_dev_max_rel", dev, kind="max", tolerance=0.05, unit="-",
                     wall_s=run.solver_wall_s, note="bounded (a blow-up grows without bound)")
    for f in UNSTABLE:
        out = case_out / f"dt_{f}x"
        out.mkdir(parents=True, exist_ok=True)
        cmd = [str(qdemsph.binary), "run", str(HERE / "scene.yaml"), "--out", str(out), "--quiet",
               "--set", f"run.dt={f * crit!r}"]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        (out / "harness.log").write_text(f"$ {' '.join(cmd)}\n{proc.stdout}\n{proc.stderr}")
        checks.check(f"x{f}.exit_code", proc.returncode, kind="abs", reference=2, tolerance=0, unit="-",
                     note=proc.stderr.strip()[:300])
        ok = "exceeds the stability limit" in proc.stderr and "tet " in proc.stderr
        checks.check(f"x{f}.message_names_limit", 1.0 if ok else 0.0, kind="min", tolerance=1.0, unit="bool",
                     note=proc.stderr.strip()[:300])
        checks.check(f"x{f}.no_steps_taken", 0.0 if (out / "fields.h5").exists() else 1.0, kind="min",
                     tolerance=1.0, unit="bool", note="refused before any output")
    checks.series("hard_dt_sweep", "max |E/E0 - 1|", STABLE, devs, style="points", yscale="log",
                  title="dt sweep: energy deviation vs dt / stability limit", xlabel="dt / limit",
                  ylabel="max |E/E0 - 1|")
    checks.require()
