"""MPI domain decomposition end to end (issue 8): `mpirun -np N qdemsph run` writes the same
probes.csv and fields.h5 as one process, and summary.json's `parallel` object (the contract
with scaling/) holds its records. See README.md."""
import shutil
from pathlib import Path

import numpy as np
import pytest

from harness import must

HERE = Path(__file__).resolve().parent
PARALLEL_KEYS = {"ranks", "curve", "rebalances", "imbalance", "imbalance_initial", "migrated_bytes",
                 "halo_bytes_per_step", "owned_vertices", "owned_tets", "phases_max", "phases_mean",
                 "rebalance_log"}
PHASES = {"elements", "integration", "contact", "sph", "halo", "migration", "balance", "output"}
# Rebalance (and migrate) at every measurement so that the run crosses many decompositions.
REBALANCE = ["parallel.rebalance_every=25", "parallel.rebalance_threshold=0"]


def fields(out):
    import h5py

    with h5py.File(out / "fields.h5", "r") as f:
        return {k: (np.asarray(f["steps"][k]["position"]), np.asarray(f["steps"][k]["velocity"]),
                    np.asarray(f["steps"][k]["von_mises"])) for k in sorted(f["steps"].keys())}


def mpi_available(qdemsph):
    import subprocess

    v = subprocess.run([str(qdemsph.binary), "version"], capture_output=True, text=True).stdout
    return shutil.which("mpirun") is not None and "mpi" in v


@pytest.mark.parametrize("ranks,curve", [(2, "hilbert"), pytest.param(4, "peano", marks=pytest.mark.full),
                                         pytest.param(3, "morton", marks=pytest.mark.full)])
def test_same_as_one_rank(ranks, curve, qdemsph, checks, case_out):
    if not mpi_available(qdemsph):
        pytest.skip("qdemsph built without MPI, or no mpirun")
    one = must(qdemsph.run, HERE / "scene.yaml", case_out / "np1")
    many = must(qdemsph.run, HERE / "scene.yaml", case_out / f"np{ranks}",
                sets=REBALANCE + [f"parallel.curve={curve}"], ranks=ranks)
    m = f"np{ranks}."
    checks.check(m + "completed", 1.0 if many.status == "completed" else 0.0, kind="min", tolerance=1.0,
                 unit="bool")
    p1, pn = one.probes(), many.probes()
    diff = max(float(np.max(np.abs(p1[k] - pn[k]))) for k in p1)
    checks.check(m + "probes_max_diff", diff, kind="max", tolerance=0.0,
                 note="every probe and energy column, every row: identical to one rank")
    f1, fn = fields(one.out), fields(many.out)
    checks.check(m + "frames", len(fn), kind="abs", reference=len(f1), tolerance=0)
    dx = max(float(np.max(np.abs(f1[k][0] - fn[k][0]))) for k in f1)
    dv = max(float(np.max(np.abs(f1[k][1] - fn[k][1]))) for k in f1)
    ds = max(float(np.max(np.abs(f1[k][2] - fn[k][2]))) for k in f1)
    checks.check(m + "position_max_diff", dx, kind="max", tolerance=0.0, unit="m")
    checks.check(m + "velocity_max_diff", dv, kind="max", tolerance=0.0, unit="m/s")
    checks.check(m + "von_mises_max_diff", ds, kind="max", tolerance=0.0, unit="Pa")
    checks.check(m + "contact_max_overlap", many.summary["contact"]["max_overlap_ever"], kind="rel",
                 reference=one.summary["contact"]["max_overlap_ever"], tolerance=0.0, unit="m")

    par = many.summary.get("parallel", {})
    checks.check(m + "parallel_keys_missing", len(PARALLEL_KEYS - set(par)), kind="max", tolerance=0,
                 note="summary.json parallel object: the keys scaling/ reads")
    checks.check(m + "parallel_keys_extra", len(set(par) - PARALLEL_KEYS), kind="max", tolerance=0)
    checks.check(m + "ranks", par.get("ranks", 0), kind="abs", reference=ranks, tolerance=0)
    checks.check(m + "phases", len(PHASES - set(par.get("phases_max", {}))), kind="max", tolerance=0)
    nfv = one.summary["parallel"]["owned_vertices"][0]
    nft = one.summary["parallel"]["owned_tets"][0]
    checks.check(m + "owned_vertices_sum", sum(par.get("owned_vertices", [])), kind="abs", reference=nfv,
                 tolerance=0, note="every free vertex owned once")
    checks.check(m + "owned_tets_sum", sum(par.get("owned_tets", [])), kind="abs", reference=nft,
                 tolerance=0, note="every free tet home once")
    checks.check(m + "rebalances", par.get("rebalances", 0), kind="min", tolerance=2)
    checks.check(m + "rebalance_log", len(par.get("rebalance_log", [])), kind="abs",
                 reference=par.get("rebalances", -1), tolerance=0)
    checks.check(m + "halo_bytes_per_step", par.get("halo_bytes_per_step", 0), kind="min", tolerance=1.0,
                 unit="B")
    checks.info(m + "migrated_bytes", par.get("migrated_bytes", 0), unit="B")
    checks.info(m + "imbalance", par.get("imbalance", np.nan))
    checks.info(m + "wall", many.solver_wall_s, unit="s", wall_s=many.solver_wall_s)
    checks.require()


def test_one_rank_reports_parallel_object(qdemsph, checks, case_out):
    """A plain run (no mpirun) writes the same object with ranks = 1."""
    run = must(qdemsph.run, HERE / "scene.yaml", case_out / "plain", sets=["run.end_time=0.002"])
    par = run.summary.get("parallel", {})
    checks.check("plain.parallel_keys", len(PARALLEL_KEYS ^ set(par)), kind="max", tolerance=0)
    checks.check("plain.ranks", par.get("ranks", 0), kind="abs", reference=1, tolerance=0)
    checks.check("plain.rebalances", par.get("rebalances", -1), kind="abs", reference=0, tolerance=0)
    checks.require()
