"""The solver's physics unit tests that have a number worth reading, brought into the report:
patch test, momentum, energy drift over 100 periods, Kelvin-Voigt damping ratio, dt
stability and blow-up detection, static cantilever refinement. The checks themselves live
in solver/tests (GoogleTest); this case runs them and records the numbers they print."""
import re
import subprocess
import time

import pytest

TESTS = "PatchTest.*:Dynamics.*:Statics.*:Element*"
PATTERNS = {
    "patch_iterations": (r"patch: (\d+) iterations", "steps"),
    "energy_drift_100_periods": (r"energy drift over .*?: ([0-9.e+-]+)", "-"),
    "kelvin_voigt_zeta": (r"log decrement: zeta ([0-9.e+-]+)", "-"),
    "kelvin_voigt_zeta_theory": (r"eta omega/\(2E\) ([0-9.e+-]+)", "-"),
}


def test_foundation_unit_checks(qdemsph, checks, case_out):
    binary = qdemsph.binary.parent / "qdemsph_tests"
    if not binary.exists():
        pytest.fail(f"{binary} not built (make builds it)", pytrace=False)
    t0 = time.time()
    proc = subprocess.run([str(binary), f"--gtest_filter={TESTS}", "--gtest_color=no"],
                          capture_output=True, text=True, timeout=900)
    wall = time.time() - t0
    (case_out / "gtest.log").write_text(proc.stdout + proc.stderr)
    passed = re.findall(r"^\[       OK \] (\S+)", proc.stdout, re.M)
    failed = re.findall(r"^\[  FAILED  \] (\S+) \(", proc.stdout, re.M)
    for name in passed:
        checks.check("gtest." + name, 1.0, kind="min", tolerance=1.0, unit="bool")
    for name in failed:
        checks.check("gtest." + name, 0.0, kind="min", tolerance=1.0, unit="bool")
    checks.check("gtest_ran", len(passed) + len(failed), kind="min", tolerance=10, unit="tests",
                 wall_s=wall)
    for metric, (pattern, unit) in PATTERNS.items():
        m = re.search(pattern, proc.stdout)
        checks.info(metric, float(m.group(1)) if m else float("nan"), unit=unit)
    cells, ratios = [], []
    for m in re.finditer(r"cells \[(\d+), \d+, \d+\]\s+tip \S+\s+/EB (\S+)", proc.stdout):
        cells.append(int(m.group(1)))
        ratios.append(float(m.group(2)))
    if cells:
        checks.series("cantilever_unit_refinement", "qdemsph linear, static", cells, ratios,
                      xlabel="cells along the beam", ylabel="tip deflection / Euler-Bernoulli")
    checks.require()
