"""Hard case: near-incompressible material (nu = 0.49).

Static tip deflection of the clamped cantilever for nu = 0.3 and 0.49 against Timoshenko beam
theory (volumetric locking of linear tets: recorded, and the ratio must be in (0, 1.05]);
the explicit dynamic run at nu = 0.49 (SVK, suddenly applied load) must complete with the
energy balance kept. See README.md."""
from pathlib import Path

import numpy as np

from harness import must

HERE = Path(__file__).resolve().parent
E, L, B, P = 1.0e7, 1.0, 0.1, 1.0  # scene.yaml: E, length, square side, tip load (100 Pa x 0.01 m^2)
I_ = B**4 / 12.0


def timoshenko(nu):
    g = E / (2.0 * (1.0 + nu))
    return P * L**3 / (3.0 * E * I_) + P * L / (5.0 / 6.0 * g * B * B)


def test_locking_and_stability(qdemsph, checks, case_out):
    ratio = {}
    for nu in (0.3, 0.49):
        run = must(qdemsph.run, HERE / "scene.yaml", case_out / f"static_nu{nu}", sets=[f"materials.solid.nu={nu}"])
        st = run.summary.get("static", {})
        checks.check(f"nu{nu}.static_converged", 1.0 if st.get("converged") else 0.0, kind="min", tolerance=1.0,
                     unit="bool", note=f"{st}")
        w = -float(run.probes()["tip_z"][-1])
        ratio[nu] = w / timoshenko(nu)
        checks.check(f"nu{nu}.tip_over_timoshenko", ratio[nu], kind="range", tolerance=[0.02, 1.05], unit="-",
                     wall_s=run.solver_wall_s, note=f"w = {w:.5e} m, Timoshenko {timoshenko(nu):.5e} m "
                     "(linear tets are stiff in bending: < 1 is locking)")
        checks.info(f"nu{nu}.relax_iterations", st.get("iterations", np.nan), unit="steps")
    checks.info("locking_factor_nu049_over_nu03", ratio[0.49] / ratio[0.3], unit="-",
                note="extra stiffening from near-incompressibility on the same mesh")

    dyn = must(qdemsph.run, HERE / "scene.yaml", case_out / "dynamic_nu0.49",
               sets=["run.mode=dynamic", "materials.solid.law=svk", "materials.solid.viscosity=1000",
                     "run.end_time=0.05"])
    checks.check("dynamic.completed", 1.0 if dyn.status == "completed" else 0.0, kind="min", tolerance=1.0,
                 unit="bool", note=f"status={dyn.status} {dyn.summary.get('error', '')}")
    p = dyn.probes()
    scale = float(np.max(np.abs(p["potential"])))
    bal = float(np.max(np.abs(p["total"])) / scale) if scale > 0 else np.nan
    checks.check("dynamic.energy_balance_rel", bal, kind="max", tolerance=1e-4, unit="-",
                 wall_s=dyn.solver_wall_s, note="|kinetic + strain + load potential + dissipated| / max |potential|")
    checks.info("dynamic.max_tip_over_static", float(np.max(-p["tip_z"]) / (ratio[0.49] * timoshenko(0.49))),
                unit="-", note="0.05 s is ~1/12 of the first bending period: the tip is still moving down")
    checks.info("dynamic.dt", dyn.summary.get("dt", np.nan), unit="s")
    meta = dict(title="Tip deflection / Timoshenko theory (20x2x2 box, linear tets)", xlabel="nu",
                ylabel="w / w_Timoshenko")
    checks.series("hard_incompressible", "qdemsph static", list(ratio), list(ratio.values()), style="points", **meta)
    checks.series("hard_incompressible", "theory", [0.3, 0.49], [1.0, 1.0], style="hline", **meta)
    checks.series("hard_incompressible_dyn", "tip z (nu = 0.49, SVK, sudden load)", p["time"], p["tip_z"],
                  style="line", title="nu = 0.49 explicit run", xlabel="t (s)", ylabel="uz (m)")
    checks.require()
