"""Hard case: energy drift over 10^5 (quick tier) or 10^6 (--full) velocity-Verlet steps of an
undamped vibrating cantilever. Verlet is symplectic: the total energy must oscillate at
O(dt^2) around its initial value without a secular trend. See README.md."""
from pathlib import Path

import numpy as np

from harness import must

HERE = Path(__file__).resolve().parent
SAFETY = 0.5  # dt = 0.5 x the stability limit (the solver's default)


def test_energy_drift(qdemsph, checks, case_out, tier):
    n = 10**6 if tier == "full" else 10**5
    probe = must(qdemsph.run, HERE / "scene.yaml", case_out / "probe_dt", sets=["run.end_time=1e-9"])
    dt = SAFETY * float(probe.summary["dt_critical"])
    end = n * dt
    run = must(qdemsph.run, HERE / "scene.yaml", case_out / "run",
               sets=[f"run.dt={dt!r}", f"run.end_time={end!r}", f"output.probes_every={end / 2000!r}"])
    checks.check("completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0,
                 unit="bool", note=f"status={run.status} {run.summary.get('error', '')}")
    steps = int(run.summary.get("steps", 0))
    checks.check("steps", steps, kind="abs", reference=n, tolerance=1, unit="steps")
    p = run.probes()
    t, e = p["time"], p["total"]
    e0 = e[0]
    dev = (e - e0) / e0
    checks.check("energy_dev_max_rel", float(np.max(np.abs(dev))), kind="max", tolerance=5.0e-3, unit="-",
                 wall_s=run.solver_wall_s, note="bounded O(dt^2) oscillation of the Verlet energy")
    k = max(len(e) // 10, 1)
    secular = float(abs(np.mean(dev[-k:]) - np.mean(dev[1:k + 1])))
    checks.check("energy_drift_secular_rel", secular, kind="max", tolerance=1.0e-4, unit="-",
                 note="mean of the last 10 % of the run minus mean of the first 10 %")
    slope = float(np.polyfit(t, dev, 1)[0] * (n * dt) / n * 1e6)
    checks.info("energy_drift_per_1e6_steps", slope, unit="-", note="least-squares slope of E/E0 - 1")
    checks.info("steps_per_s", run.summary.get("steps_per_s", np.nan), unit="1/s", wall_s=run.solver_wall_s)
    checks.series("hard_long_run", f"{n:.0e} steps, dt = {SAFETY} x limit", t / dt, dev, style="line",
                  title="Long run: relative total-energy deviation", xlabel="step", ylabel="E/E0 - 1")
    checks.require()
