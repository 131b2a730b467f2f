"""MPI domain decomposition end to end (issue 8): `mpirun -np N qdemsph run` writes the same
probes.csv and fields.h5 as one process, and summary.json's `parallel` object (the contract
with scaling/) holds its records; a checkpoint written on 2 ranks holds the one-rank state and
continues on 1 or 2 ranks exactly as the one-rank run. See README.md."""
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from harness import must
from harness.qdemsph import mpirun_command

HERE = Path(__file__).resolve().parent
PARALLEL_KEYS = {"ranks", "curve", "rebalances", "rebuilds", "contact_slack", "imbalance", "imbalance_initial",
                 "imbalance_modelled", "migrated_bytes",
                 "halo_bytes_per_step", "fluid_halo_bytes_per_step", "fluid_migrated_bytes", "fluid_rebuilds", "fluid_recuts", "fluid_skin",
                 "setup_s",
                 "owned_vertices",
                 "owned_tets", "phases_max", "phases_mean", "rebalance_log", "rebuild_log", "phases_by_rank"}
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
    by_rank = par.get("phases_by_rank", [])
    checks.check(m + "phases_by_rank", len(by_rank), kind="abs", reference=ranks, tolerance=0,
                 note="one entry per rank")
    checks.check(m + "phases_by_rank_missing", sum(len(PHASES - set(r)) for r in by_rank), kind="max",
                 tolerance=0)
    checks.check(m + "phases_by_rank_max", max((r.get("elements", 0) for r in by_rank), default=-1), kind="rel",
                 reference=par.get("phases_max", {}).get("elements", 0), tolerance=1e-12,
                 note="the largest rank's elements time is phases_max's")
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
    checks.info(m + "imbalance_modelled", par.get("imbalance_modelled", np.nan))
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


def checkpoint_state(path):
    """The state datasets of a checkpoint file (/solid, /contact history_*) and the contact
    dissipation."""
    import h5py

    with h5py.File(path, "r") as f:
        out = {f"solid/{k}": np.asarray(f["solid"][k]) for k in f["solid"]}
        out.update({f"contact/{k}": np.asarray(f["contact"][k]) for k in f["contact"] if k.startswith("history_")})
        return out, float(f["contact"].attrs["dissipated"])


def test_checkpoint_restarts_on_other_rank_counts(qdemsph, checks, case_out):
    """`mpirun -np 2` writes checkpoints every 30 steps and stops at step 149 (t = 0.03 s, with
    its own last rows and frame); restarted from the one of step 30 (the cubes on the block:
    66 history entries) on one process and on 2 ranks, both continue exactly as the
    uninterrupted one-rank run, whose own checkpoint of step 30 holds the same state. A
    checkpoint of another scene is refused on 2 ranks."""
    if not mpi_available(qdemsph):
        pytest.skip("qdemsph built without MPI, or no mpirun")
    scene = HERE / "scene.yaml"
    every = "output.checkpoint={every_steps: 30, keep: 10}"
    name = "checkpoint_0000000030.h5"
    one = must(qdemsph.run, scene, case_out / "np1", sets=[every])
    first = must(qdemsph.run, scene, case_out / "np2_first", sets=REBALANCE + [every, "run.end_time=0.03"], ranks=2)
    a, da = checkpoint_state(one.out / "checkpoints" / name)
    b, db = checkpoint_state(first.out / "checkpoints" / name)
    differing = sorted(k for k in a.keys() | b.keys() if k not in a or k not in b or not np.array_equal(a[k], b[k]))
    checks.check("checkpoint.datasets_differing", len(differing), kind="max", tolerance=0, unit="datasets",
                 note=f"the 2-rank and the one-rank checkpoint of step 30, bit for bit: {len(a)} datasets, "
                      f"{len(a['contact/history_type'])} history entries; differing: {differing}")
    checks.check("checkpoint.contact_dissipated", db, kind="rel", reference=da, tolerance=1e-12, unit="J",
                 note="a sum over ranks: round-off")
    for ranks in (1, 2):
        out = case_out / f"restart_np{ranks}"
        shutil.rmtree(out, ignore_errors=True)
        shutil.copytree(first.out, out)
        run = must(qdemsph.run, scene, out, sets=REBALANCE, ranks=ranks if ranks > 1 else None,
                   restart=out / "checkpoints" / name)
        m = f"restart_np{ranks}."
        checks.check(m + "completed", 1.0 if run.status == "completed" else 0.0, kind="min", tolerance=1.0,
                     unit="bool")
        checks.check(m + "from_step", run.summary.get("restarted_from", {}).get("step", -1), kind="abs",
                     reference=30, tolerance=0, unit="step")
        p1, pn = one.probes(), run.probes()
        checks.check(m + "rows", len(pn["time"]), kind="abs", reference=len(p1["time"]), tolerance=0, unit="rows")
        diff = max(float(np.max(np.abs(p1[k] - pn[k]))) for k in p1) if len(pn["time"]) == len(p1["time"]) else np.inf
        checks.check(m + "probes_max_diff", diff, kind="max", tolerance=0.0,
                     note="every probe and energy column, every row: identical to the uninterrupted one-rank run")
        f1, fn = fields(one.out), fields(run.out)
        checks.check(m + "frames", len(fn), kind="abs", reference=len(f1), tolerance=0)
        for i, what, unit in ((0, "position", "m"), (1, "velocity", "m/s"), (2, "von_mises", "Pa")):
            d = max(float(np.max(np.abs(f1[k][i] - fn[k][i]))) if k in fn else np.inf for k in f1)
            checks.check(m + what + "_max_diff", d, kind="max", tolerance=0.0, unit=unit)

    # The 2-rank checkpoint against a changed scene, on 2 ranks: exit code 2, one message.
    out = case_out / "restart_np2"
    cmd = mpirun_command(2) + [str(qdemsph.binary), "run", str(scene), "--out", str(out), "--quiet",
                               "--restart", str(out / "checkpoints" / name), "--set", "materials.m.E=2e6"]
    env = {**os.environ, "OMPI_MCA_rmaps_base_oversubscribe": "1", "PMIX_MCA_pcompress_base_silence_warning": "1"}
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env)
    checks.check("changed_scene.exit_code", proc.returncode, kind="abs", reference=2, tolerance=0, unit="-",
                 note=proc.stderr.strip()[:300])
    named = "material 'm': checkpoint has law svk, E 1000000" in proc.stderr
    checks.check("changed_scene.messages", proc.stderr.count("does not match scene") if named else 0, kind="abs",
                 reference=1, tolerance=0, unit="-", note="reported once (by rank 0), naming material 'm' and E")
    checks.require()


def fluid_checkpoint(path):
    """The /fluid datasets of a checkpoint file."""
    import h5py

    with h5py.File(path, "r") as f:
        return {k: np.asarray(f["fluid"][k]) for k in f["fluid"] if isinstance(f["fluid"][k], h5py.Dataset)}


# fluid.csv columns that are sums over particles (reduced over ranks: round-off) and those
# that are maxima or positions (exact).
FLUID_SUMS = ("kinetic", "px", "py", "pz")


def test_fluid_same_as_one_rank(qdemsph, checks, case_out):
    """SPH on 2 ranks (the partition cut again every 25 steps): every fluid.h5 frame (positions,
    velocities, pressures, densities, ids, types, in the file's order) identical to one process,
    fluid.csv's maxima and positions identical and its sums (kinetic energy, momentum) to
    round-off; the 2-rank checkpoint of step 50 holds the one-rank fluid state bit for bit, and
    2 ranks restarted from the one-rank checkpoint continue exactly as the one-rank run."""
    from harness.sph import fluid_csv, fluid_frames

    if not mpi_available(qdemsph):
        pytest.skip("qdemsph built without MPI, or no mpirun")
    scene = HERE / "scene_fluid.yaml"
    every = "output.checkpoint={every_steps: 50, keep: 5}"
    one = must(qdemsph.run, scene, case_out / "fluid_np1", sets=[every])
    two = must(qdemsph.run, scene, case_out / "fluid_np2", sets=REBALANCE + [every], ranks=2)
    checks.check("fluid.np2.completed", 1.0 if two.status == "completed" else 0.0, kind="min", tolerance=1.0,
                 unit="bool")

    def frames_diff(a_out, b_out):
        fa, fb = fluid_frames(a_out), fluid_frames(b_out)
        if len(fa) != len(fb):
            return np.inf, len(fb)
        d = 0.0
        for a, b in zip(fa, fb):
            for k in ("x", "v", "p", "rho", "type", "id"):
                d = max(d, float(np.max(np.abs(a[k].astype(float) - b[k].astype(float)))))
        return d, len(fb)

    d, n = frames_diff(one.out, two.out)
    checks.check("fluid.np2.frames", n, kind="abs", reference=len(fluid_frames(one.out)), tolerance=0)
    checks.check("fluid.np2.fluid_h5_max_diff", d, kind="max", tolerance=0.0,
                 note="positions, velocities, pressures, densities, ids and types of every frame, in file order")
    c1, c2 = fluid_csv(one.out), fluid_csv(two.out)
    exact = max(float(np.max(np.abs(c1[k] - c2[k]))) for k in c1 if k not in FLUID_SUMS)
    checks.check("fluid.np2.csv_exact_columns_max_diff", exact, kind="max", tolerance=0.0,
                 note="time, v_max, rho_dev, x_max, y_max, dt_limit, body force")
    scale = float(np.max(np.abs(c1["kinetic"]))) + 1e-300
    sums = max(float(np.max(np.abs(c1[k] - c2[k]))) for k in FLUID_SUMS) / scale
    checks.check("fluid.np2.csv_sums_rel_diff", sums, kind="max", tolerance=1e-12,
                 note="kinetic energy and momentum: sums over ranks (round-off), relative to the largest kinetic")

    name = "checkpoint_0000000050.h5"
    a, b = fluid_checkpoint(one.out / "checkpoints" / name), fluid_checkpoint(two.out / "checkpoints" / name)
    differing = sorted(k for k in a.keys() | b.keys() if k not in a or k not in b or not np.array_equal(a[k], b[k]))
    checks.check("fluid.checkpoint.datasets_differing", len(differing), kind="max", tolerance=0, unit="datasets",
                 note=f"the 2-rank and the one-rank checkpoint of step 50: {sorted(a)}; differing: {differing}")

    out = case_out / "fluid_restart_np2"
    shutil.rmtree(out, ignore_errors=True)
    shutil.copytree(one.out, out)
    run = must(qdemsph.run, scene, out, sets=REBALANCE + [every], ranks=2, restart=out / "checkpoints" / name)
    d, n = frames_diff(one.out, run.out)
    checks.check("fluid.restart_np2.fluid_h5_max_diff", d, kind="max", tolerance=0.0,
                 note="a one-rank checkpoint of step 50 continued on 2 ranks: every frame as the uninterrupted run")
    p1, p2 = one.summary["parallel"], two.summary["parallel"]
    checks.check("fluid.np1.fluid_bytes", p1["fluid_halo_bytes_per_step"] + p1["fluid_migrated_bytes"], kind="max",
                 tolerance=0, unit="B", note="one process sends nothing")
    checks.check("fluid.np2.fluid_halo_bytes_per_step", p2["fluid_halo_bytes_per_step"], kind="min", tolerance=1.0,
                 unit="B", note="the fluid's ghost fill and refreshes per fluid evaluation, all ranks (docs/parallel.md)")
    checks.check("fluid.np2.fluid_migrated_bytes", p2["fluid_migrated_bytes"], kind="min", tolerance=1.0, unit="B")
    checks.check("fluid.np1.fluid_rebuilds", p1["fluid_rebuilds"], kind="max", tolerance=0,
                 note="one process has no fluid layout to rebuild")
    checks.check("fluid.np2.fluid_rebuilds", p2["fluid_rebuilds"], kind="min", tolerance=2,
                 note="the first layout and at least one re-cut (parallel.rebalance_every 25, threshold 0)")
    checks.info("fluid.np2.wall", two.solver_wall_s, unit="s", wall_s=two.solver_wall_s)
    checks.require()
