"""Run the FEniCSx reference script (references/fenicsx/cantilever.py) and load its outputs.

The script runs in a child process of the same interpreter (Debian's /usr/bin/python3, which
has dolfinx): form compilation and PETSc stay out of the pytest process, and a crash there
is reported as a test failure with the script's own message."""
from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from .paths import FENICSX, FENICSX_RESULTS

SCRIPT = FENICSX / "cantilever.py"


class FenicsxError(RuntimeError):
    pass


def solve_cantilever(out, degree, mesh=None, box=None, E=1.0e7, nu=0.3, traction=-100.0,
                     length=None, timeout_s=1800):
    """Solve; returns (result dict, vertex table (N,7): vertex,x,y,z,ux,uy,uz, wall_s)."""
    out = Path(out)
    cmd = [sys.executable, str(SCRIPT), "--degree", str(degree), "--E", repr(E), "--nu", repr(nu),
           "--traction", repr(traction), "--out", str(out)]
    if mesh is not None:
        cmd += ["--mesh", str(mesh)]
    elif box is not None:
        cmd += ["--box", *map(str, box)]
    else:
        raise ValueError("give mesh= or box=")
    if length is not None:
        cmd += ["--length", repr(length)]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout_s)
    except subprocess.TimeoutExpired as e:
        raise FenicsxError(f"timed out after {timeout_s} s: {' '.join(cmd)}") from e
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    (out / f"fenicsx_p{degree}.log").write_text(f"$ {' '.join(cmd)}\n{proc.stdout}\n{proc.stderr}")
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout)[-2000:]
        raise FenicsxError(f"FEniCSx reference failed (exit {proc.returncode}): {' '.join(cmd)}\n{tail}")
    result = json.loads((out / f"result_p{degree}.json").read_text())
    table = np.loadtxt(out / f"displacement_p{degree}.csv", delimiter=",", skiprows=1, ndmin=2)
    return result, table, wall


def stored_results():
    """references/fenicsx/results/tip_deflection.json (written by make_references)."""
    path = FENICSX_RESULTS / "tip_deflection.json"
    if not path.exists():
        raise FenicsxError(f"{path} is missing: run `make references`")
    return json.loads(path.read_text())
