"""Checkpoint/restart through the binary (`output.checkpoint`, `qdemsph run --restart`).

1. Bit-identical continuation (CPU backend): for an element-only, a contact, an SPH scene and
   an SPH scene coupled to a body (the checkpoint holds the fluid's force on the body, fc),
   one uninterrupted run against a run stopped half-way (its own end_time, so it also wrote
   final rows and frames past the checkpoint) and continued with `--restart latest`.
   probes.csv, fluid.csv and the XDMF indexes must be byte-identical, every fields.h5 and
   fluid.h5 frame bit-identical, the final energies equal.
2. Kill loop: a contact run writing a checkpoint every step (the fsync makes the writes most
   of the wall time) is killed with SIGKILL at random times and restarted from `latest`, again
   and again. After every kill each checkpoint_*.h5 present must be complete and readable;
   at the end the chain of restarts must reproduce the uninterrupted run's probes.csv byte for
   byte and its final state bit for bit.
3. A checkpoint of another scene (changed E) is refused: exit code 2, a message naming the
   material and both values, and no output file touched."""
import os
import random
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

HERE = Path(__file__).resolve().parent


def cli(qdemsph, scene, out, *args, sets=()):
    cmd = [str(qdemsph.binary), "run", str(scene), "--out", str(out), "--quiet", "--backend", "cpu"]
    cmd += list(args)
    for s in sets:
        cmd += ["--set", s]
    return cmd


def run(qdemsph, scene, out, *args, sets=(), log=None):
    cmd = cli(qdemsph, scene, out, *args, sets=sets)
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if log is not None:
        with open(log, "a") as f:
            f.write(f"$ {' '.join(cmd)}\nexit {proc.returncode}\n{proc.stdout}{proc.stderr}\n")
    return proc


def frames(path, names):
    """{frame: {name: array}} of a series file (fields.h5 / fluid.h5)."""
    out = {}
    with h5py.File(path, "r") as f:
        for k in sorted(f["steps"].keys()):
            out[k] = {n: f["steps"][k][n][()] for n in names}
            out[k]["step"] = int(f["steps"][k].attrs["step"])
    return out


def identical_frames(a, b):
    """Number of frames that differ in any bit (or exist in one file only)."""
    bad = len(set(a) ^ set(b))
    for k in set(a) & set(b):
        bad += any(not np.array_equal(a[k][n], b[k][n]) for n in a[k])
    return bad


@pytest.mark.parametrize("scene", ["beam", "contact", "dam", "coupled"])
def test_restart_is_bit_identical(qdemsph, checks, case_out, scene):
    path = HERE / f"scene_{scene}.yaml"
    log = case_out / "harness.log"
    full, part = case_out / "full", case_out / "part"
    t0 = time.time()
    p = run(qdemsph, path, full, log=log)
    assert p.returncode == 0, p.stderr
    end = {"beam": 0.02, "contact": 0.02, "dam": 0.03, "coupled": 0.03}[scene]
    fluid = scene in ("dam", "coupled")
    every = "every_steps: 10"
    p = run(qdemsph, path, part, sets=[f"run.end_time={end / 2}", f"output.checkpoint={{{every}, keep: 2}}"],
            log=log)
    assert p.returncode == 0, p.stderr
    stop_steps = int(__import__("json").loads((part / "summary.json").read_text())["steps"])
    p = run(qdemsph, path, part, "--restart", "latest", log=log)
    assert p.returncode == 0, p.stderr
    wall = time.time() - t0
    import json
    sf, sp = json.loads((full / "summary.json").read_text()), json.loads((part / "summary.json").read_text())
    restarted = sp.get("restarted_from", {}).get("step", -1)
    checks.info("restart_step", restarted, unit="step", note=f"first run stopped at step {stop_steps} of {sf['steps']}")
    checks.check("restarted_mid_run", 1.0 if 0 < restarted < sf["steps"] else 0.0, kind="min", tolerance=1.0,
                 unit="bool", note=f"restarted from step {restarted}")
    texts = ["probes.csv", "fields.xdmf"] + (["fluid.csv", "fluid.xdmf"] if fluid else [])
    for name in texts:
        same = (full / name).read_bytes() == (part / name).read_bytes()
        checks.check(f"{name}_identical", 1.0 if same else 0.0, kind="min", tolerance=1.0, unit="bool",
                     note=f"{(full / name).stat().st_size} vs {(part / name).stat().st_size} bytes")
    fa = frames(full / "fields.h5", ["position", "velocity", "stress"])
    fb = frames(part / "fields.h5", ["position", "velocity", "stress"])
    checks.check("field_frames_differing", identical_frames(fa, fb), kind="abs", reference=0, tolerance=0,
                 unit="frames", note=f"{len(fa)} frames")
    if fluid:
        ga = frames(full / "fluid.h5", ["position", "velocity", "density", "id"])
        gb = frames(part / "fluid.h5", ["position", "velocity", "density", "id"])
        checks.check("fluid_frames_differing", identical_frames(ga, gb), kind="abs", reference=0, tolerance=0,
                     unit="frames", note=f"{len(ga)} frames")
    checks.check("final_energy_difference", abs(sf["energies"]["total"] - sp["energies"]["total"]), kind="abs",
                 reference=0, tolerance=0, unit="J", wall_s=wall,
                 note=f"total {sf['energies']['total']!r} vs {sp['energies']['total']!r}")
    checks.require()


def readable(path):
    """True when a checkpoint file is complete: its attributes and every dataset read back."""
    try:
        with h5py.File(path, "r") as f:
            if f.attrs["format"] != b"qdemsph checkpoint" and f.attrs["format"] != "qdemsph checkpoint":
                return False
            n = f["solid/vertex_gid"].shape[0]
            ok = all(f["solid"][k].shape[0] == n for k in ("x", "v", "f", "dissipated"))
            for g in ("solid", "contact"):
                for k in f[g]:
                    f[g][k][()]
            int(f["output"].attrs["probes_bytes"])
            return ok and int(f.attrs["step"]) >= 0
    except Exception:  # noqa: BLE001 - any failure to read is what we count
        return False


def test_kill_during_checkpoint_writes(qdemsph, checks, case_out, tier):
    scene = HERE / "scene_contact.yaml"
    log = case_out / "harness.log"
    end = "run.end_time=0.04"
    ref, out = case_out / "reference", case_out / "killed"
    p = run(qdemsph, scene, ref, sets=[end], log=log)
    assert p.returncode == 0, p.stderr
    ckdir = out / "checkpoints"
    every_step = "output.checkpoint={every_steps: 1, keep: 2}"
    rng = random.Random(20240611)
    iterations = 100 if tier == "full" else 20
    unreadable, tmp_left, finished_early, steps_seen = 0, 0, 0, []
    t0 = time.time()
    for it in range(iterations):
        before = {f.name for f in ckdir.glob("checkpoint_*")}
        restart = ["--restart", "latest"] if any(n.endswith(".h5") for n in before) else []
        cmd = cli(qdemsph, scene, out, *restart, sets=[end, every_step])
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        # Wait until this process writes checkpoints (past its start-up), then kill it at a
        # random moment of its write cycle.
        deadline = time.time() + 60
        while proc.poll() is None and time.time() < deadline:
            if {f.name for f in ckdir.glob("checkpoint_*")} - before:
                break
            time.sleep(0.002)
        time.sleep(rng.uniform(0.0, 0.1))
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
        else:
            finished_early += 1
        _, err = proc.communicate()
        with open(log, "a") as f:
            f.write(f"[{it}] $ {' '.join(cmd)}\nexit {proc.returncode}\n{err}\n")
        if proc.returncode not in (0, -signal.SIGKILL):
            pytest.fail(f"iteration {it}: qdemsph exited {proc.returncode}: {err}")
        tmp_left += len(list(ckdir.glob("*.tmp")))
        files = sorted(ckdir.glob("checkpoint_*.h5"))
        for f in files:
            if not readable(f):
                unreadable += 1
                with open(log, "a") as fl:
                    fl.write(f"[{it}] UNREADABLE {f}\n")
        if files:
            steps_seen.append(int(files[-1].stem.split("_")[1]))
        if proc.returncode == 0:
            break  # the chain reached the end
    loop_s = time.time() - t0
    p = run(qdemsph, scene, out, "--restart", "latest", sets=[end, "output.checkpoint={every_steps: 100000}"],
            log=log)
    assert p.returncode == 0, p.stderr
    checks.info("kill_iterations", it + 1, unit="kills", note=f"{finished_early} ran to the end before the kill")
    checks.info("kills_inside_a_checkpoint_write", tmp_left, unit="kills",
                note="a checkpoint_*.tmp was left behind: the kill interrupted a write")
    checks.check("unreadable_checkpoints", unreadable, kind="abs", reference=0, tolerance=0, unit="files",
                 wall_s=loop_s, note=f"latest checkpoint step after each kill: {steps_seen[:40]}")
    checks.check("progress_through_kills", 1.0 if len(steps_seen) > 2 and steps_seen[-1] > steps_seen[0] else 0.0,
                 kind="min", tolerance=1.0, unit="bool", note="restarts advanced the run between kills")
    same = (ref / "probes.csv").read_bytes() == (out / "probes.csv").read_bytes()
    checks.check("probes_identical_after_kills", 1.0 if same else 0.0, kind="min", tolerance=1.0, unit="bool",
                 note="probes.csv of the killed-and-restarted chain vs the uninterrupted run")
    last = lambda d: max(frames(d / "fields.h5", ["position", "velocity"]).items(),
                         key=lambda kv: kv[1]["step"])[1]
    a, b = last(ref), last(out)
    checks.check("final_state_identical", 1.0 if a["step"] == b["step"] and identical_frames({0: a}, {0: b}) == 0
                 else 0.0, kind="min", tolerance=1.0, unit="bool", note=f"final frame at step {a['step']} / {b['step']}")
    checks.require()


def test_changed_scene_is_refused(qdemsph, checks, case_out):
    scene = HERE / "scene_beam.yaml"
    out = case_out / "run"
    p = run(qdemsph, scene, out, sets=["run.end_time=0.004", "output.checkpoint={every_steps: 5}"])
    assert p.returncode == 0, p.stderr
    before = {f.name: f.read_bytes() for f in out.iterdir() if f.is_file()}
    p = run(qdemsph, scene, out, "--restart", "latest", sets=["materials.rubber.E=2e6"], log=case_out / "harness.log")
    checks.check("exit_code", p.returncode, kind="abs", reference=2, tolerance=0, unit="-", note=p.stderr[:300])
    ok = ("does not match scene" in p.stderr and "material 'rubber'" in p.stderr and "E 1000000" in p.stderr
          and "E 2000000" in p.stderr)
    checks.check("message_names_material_and_values", 1.0 if ok else 0.0, kind="min", tolerance=1.0, unit="bool",
                 note=p.stderr.strip()[:400])
    after = {f.name: f.read_bytes() for f in out.iterdir() if f.is_file()}
    checks.check("outputs_untouched", 1.0 if before == after else 0.0, kind="min", tolerance=1.0, unit="bool",
                 note=", ".join(sorted(before)))
    checks.require()


def test_wall_clock_interval_writes_checkpoints(qdemsph, checks, case_out):
    """output.checkpoint.every_seconds: checkpoints by wall-clock time, the newest `keep` kept."""
    out = case_out / "run"
    p = run(qdemsph, HERE / "scene_contact.yaml", out, sets=["run.end_time=0.04",
            "output.checkpoint={every_seconds: 0.01, keep: 3}"], log=case_out / "harness.log")
    assert p.returncode == 0, p.stderr
    files = sorted((out / "checkpoints").glob("checkpoint_*.h5"))
    steps = [int(f.stem.split("_")[1]) for f in files]
    checks.check("checkpoints_kept", len(files), kind="range", tolerance=[2, 3], unit="files",
                 note=f"steps {steps}; keep 3")
    checks.check("all_readable", 1.0 if all(readable(f) for f in files) else 0.0, kind="min", tolerance=1.0,
                 unit="bool")
    checks.require()
