#!/usr/bin/python3
"""Quick live check of the YADE reference (quick tier of `make verify`, < 60 s).

Re-runs the smallest stored case, the cube sliding at v0 = 1 m/s, mu = 0.5
(`yade -n -x sliding.py --mu 0.5 --v0 1.0 --dt 1e-5 --young 1e8 --tail 0.05 --tag _live`),
and compares it with results/sliding_live.csv / .provenance.json:
  trajectory  max |x - x_ref| <= 1e-6 m and max |vx - vx_ref| <= 1e-5 m/s on every stored row
              (same rows: the run is deterministic, single-threaded; the CSV keeps 7 digits);
  stop        |d - d_ref| / d_ref <= 1e-6, |t - t_ref| <= 1e-5 s;
  analytic    |d - v0^2/(2 mu g)| / that <= 1e-3 (sanity: the physics, not just repeatability).
Exit 0 on success, 1 on a mismatch, 2 when YADE cannot be run.

Run with /usr/bin/python3: /usr/bin/python3 references/yade/check_live.py
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import common  # noqa: E402

ARGS = ["--mu", "0.5", "--v0", "1.0", "--dt", "1e-5", "--young", "1e8", "--tail", "0.05",
        "--tag", "_live"]
TOL_X, TOL_V, TOL_D_REL, TOL_T, TOL_ANALYTIC = 1e-6, 1e-5, 1e-6, 1e-5, 1e-3


def main():
    yade = shutil.which("yade")
    if yade is None:
        print("check_live: yade not found on PATH")
        return 2
    ref_csv = os.path.join(HERE, "results", "sliding_live.csv")
    ref_prov = os.path.join(HERE, "results", "sliding_live.provenance.json")
    tmp = tempfile.mkdtemp(prefix="yade_live_")
    t0 = time.time()
    try:
        proc = subprocess.run([yade, "-n", "-x", os.path.join(HERE, "sliding.py")] + ARGS
                              + ["--out", tmp], cwd=tmp, capture_output=True, text=True, timeout=58)
    except subprocess.TimeoutExpired:
        print("check_live: yade run exceeded 58 s")
        return 2
    wall = time.time() - t0
    new_csv = os.path.join(tmp, "sliding_live.csv")
    if proc.returncode != 0 or not os.path.exists(new_csv):
        print("check_live: yade failed (rc %d)\n%s" % (proc.returncode, proc.stderr[-2000:]))
        return 2
    _, ref = common.read_csv(ref_csv)
    _, new = common.read_csv(new_csv)
    with open(ref_prov) as f:
        rref = json.load(f)["results"]
    with open(os.path.join(tmp, "sliding_live.provenance.json")) as f:
        rnew = json.load(f)["results"]
    shutil.rmtree(tmp, ignore_errors=True)

    fails = []
    if len(ref) != len(new):
        fails.append("row count %d != %d" % (len(new), len(ref)))
    else:
        dx = max(abs(a[1] - b[1]) for a, b in zip(new, ref))
        dv = max(abs(a[2] - b[2]) for a, b in zip(new, ref))
        print("trajectory: max|dx| %.3g m (tol %g), max|dvx| %.3g m/s (tol %g)" % (dx, TOL_X, dv, TOL_V))
        if dx > TOL_X or dv > TOL_V:
            fails.append("trajectory differs")
    d, dr = rnew["stop_distance_m"], rref["stop_distance_m"]
    t, tr = rnew["stop_time_s"], rref["stop_time_s"]
    da = rnew["analytic_stop_distance_m"]
    print("stop distance %.7f m (stored %.7f, analytic %.7f); stop time %.6f s (stored %.6f)"
          % (d, dr, da, t, tr))
    if abs(d - dr) / dr > TOL_D_REL or abs(t - tr) > TOL_T:
        fails.append("stop distance/time differ from the stored run")
    if abs(d - da) / da > TOL_ANALYTIC:
        fails.append("stop distance off the analytic value by more than %g" % TOL_ANALYTIC)
    print("check_live: %s (%.1f s)" % ("FAIL: " + "; ".join(fails) if fails else "OK", wall))
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
