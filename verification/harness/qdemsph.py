"""Run the qdemsph binary and read what it writes (the solver's output contract).

  qdemsph run SCENE.yaml --out DIR [--set key=value ...]
      DIR/summary.json, DIR/probes.csv, DIR/fields.h5 (/mesh/points, /mesh/tets,
      /steps/<k:06d>/{displacement,velocity,stress,von_mises}, attribute `time`)
  qdemsph mesh SCENE.yaml --out DIR
      DIR/<body>.msh (Gmsh MSH 4.1 ASCII, node tag = vertex index + 1)
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


class QdemsphError(RuntimeError):
    pass


def _tail(text, n=2000):
    text = text or ""
    return text if len(text) <= n else "..." + text[-n:]


@dataclass
class RunResult:
    scene: Path
    out: Path
    summary: dict
    wall_s: float  # measured around the process by the harness
    log: str = ""
    returncode: int = 0
    _fields: tuple | None = field(default=None, repr=False)

    @property
    def status(self):
        return self.summary.get("status")

    @property
    def backend(self):
        return self.summary.get("backend", "unknown")

    @property
    def solver_wall_s(self):
        """The solver's own wall time when it reports one, else the harness's measurement."""
        w = self.summary.get("wall_s")
        return float(w) if isinstance(w, (int, float)) else self.wall_s

    def probes(self):
        """probes.csv as {column: 1-D array}."""
        path = self.out / "probes.csv"
        if not path.exists():
            raise QdemsphError(f"{path} is missing (the solver must write probes.csv)")
        data = np.genfromtxt(path, delimiter=",", names=True, dtype=float)
        data = np.atleast_1d(data)
        return {name: np.asarray(data[name]) for name in data.dtype.names}

    def final_fields(self):
        """(points (N,3), tets (M,4), displacement (N,3), time) of the last step in fields.h5."""
        if self._fields is None:
            import h5py

            path = self.out / "fields.h5"
            if not path.exists():
                raise QdemsphError(f"{path} is missing (the solver must write fields.h5)")
            with h5py.File(path, "r") as f:
                for key in ("mesh/points", "mesh/tets", "steps"):
                    if key not in f:
                        raise QdemsphError(f"{path}: no /{key}")
                steps = sorted(f["steps"].keys())
                if not steps:
                    raise QdemsphError(f"{path}: /steps is empty")
                last = f["steps"][steps[-1]]
                if "displacement" not in last:
                    raise QdemsphError(f"{path}: /steps/{steps[-1]} has no displacement")
                self._fields = (np.asarray(f["mesh/points"], dtype=float),
                                np.asarray(f["mesh/tets"], dtype=np.int64),
                                np.asarray(last["displacement"], dtype=float),
                                float(last.attrs.get("time", np.nan)))
        return self._fields


class Qdemsph:
    def __init__(self, binary, backend=None, timeout_s=1800, threads=0):
        self.binary = Path(binary)
        self.backend = backend
        self.timeout_s = timeout_s
        self.threads = threads  # > 0: passed as run.threads

    def check(self):
        if not self.binary.exists():
            raise QdemsphError(
                f"qdemsph binary not found at {self.binary}: build it first (`make`), "
                f"or pass --qdemsph PATH / set QDEMSPH")
        if not os.access(self.binary, os.X_OK):
            raise QdemsphError(f"{self.binary} is not executable")

    # Exit codes of qdemsph: 0 success, 1 internal error, 2 bad input, 3 static solve not
    # converged, 4 simulation failed. With 3 and 4 the outputs are still read (the tests then
    # fail on the summary's status, with the numbers in the report).
    RESULT_CODES = (0, 3, 4)

    def _call(self, args, out: Path, ok_codes=(0,), ranks=None):
        self.check()
        out.mkdir(parents=True, exist_ok=True)
        cmd = [str(self.binary), *map(str, args)]
        env = None
        if ranks:
            cmd = mpirun_command(ranks) + cmd
            env = {**os.environ, "OMPI_MCA_rmaps_base_oversubscribe": "1",
                   "PMIX_MCA_pcompress_base_silence_warning": "1"}
        t0 = time.perf_counter()
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=self.timeout_s, env=env)
        except subprocess.TimeoutExpired as e:
            raise QdemsphError(f"timed out after {self.timeout_s} s: {' '.join(cmd)}") from e
        wall = time.perf_counter() - t0
        log = f"$ {' '.join(cmd)}\n{proc.stdout}\n{proc.stderr}"
        (out / "harness.log").write_text(log)
        if proc.returncode not in ok_codes:
            raise QdemsphError(f"exit code {proc.returncode}: {' '.join(cmd)}\n{_tail(proc.stderr or proc.stdout)}")
        return wall, log, proc.returncode

    def run(self, scene, out, sets=(), ranks=None, restart=None):
        """Run a scene; returns RunResult. Extra `sets` are 'dotted.key=yaml_value' strings.
        ranks: run under `mpirun -np RANKS` (Open MPI; oversubscribed when the machine has fewer
        cores), on one process otherwise. restart: continue from a checkpoint (`--restart`: a
        file or "latest")."""
        scene, out = Path(scene), Path(out)
        args = ["run", scene, "--out", out, "--quiet"]
        if restart:
            args += ["--restart", restart]
        if self.backend:
            args += ["--backend", self.backend]
        if self.threads and self.threads > 0:
            args += ["--set", f"run.threads={self.threads}"]
        for s in sets:
            args += ["--set", s]
        spath = out / "summary.json"
        if spath.exists():
            spath.unlink()
        wall, log, code = self._call(args, out, ok_codes=self.RESULT_CODES, ranks=ranks)
        if not spath.exists():
            raise QdemsphError(f"{spath} was not written (exit code {code}) by: qdemsph run {scene}\n{_tail(log)}")
        summary = json.loads(spath.read_text())
        return RunResult(scene=scene, out=out, summary=summary, wall_s=wall, log=log, returncode=code)

    def mesh(self, scene, out):
        """Export each body's mesh; returns {body name: Path to .msh}."""
        scene, out = Path(scene), Path(out)
        self._call(["mesh", scene, "--out", out], out)
        found = {p.stem: p for p in sorted(out.glob("*.msh"))}
        if not found:
            raise QdemsphError(f"qdemsph mesh {scene} wrote no .msh file into {out}")
        return found


def mpirun_command(ranks):
    """`mpirun -np RANKS` (Open MPI), allowed to oversubscribe the cores (and to run as root,
    as CI containers do)."""
    import shutil

    exe = shutil.which("mpirun")
    if exe is None:
        raise QdemsphError("mpirun not found (install Open MPI: ci/install-deps.sh)")
    cmd = [exe, "--oversubscribe", "-np", str(int(ranks))]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.insert(1, "--allow-run-as-root")
    return cmd


def write_scene_variant(template, dest, **replacements):
    """Copy a scene YAML replacing flow values of keys, e.g. cells="[40, 4, 4]".

    Each key must occur exactly once as `key: value` inside a flow mapping
    (`{..., key: [..], ...}` or `{..., key: scalar}`); anything else is an error, so a changed
    scene layout cannot silently produce the unmodified scene."""
    text = Path(template).read_text()
    for key, value in replacements.items():
        pattern = re.compile(r"(\b" + re.escape(key) + r":\s*)(\[[^\]]*\]|[^,}\s]+)")
        text, n = pattern.subn(lambda m: m.group(1) + str(value), text)
        if n != 1:
            raise ValueError(f"{template}: key '{key}' found {n} times, expected exactly once")
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_text(text)
    return dest
