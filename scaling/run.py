#!/usr/bin/python3
"""Run a scaling sweep: generate each scene (scenes.py), launch `qdemsph run` on N ranks,
and write one JSON record per run.

  /usr/bin/python3 scaling/run.py cubes-weak --ranks 1,2,4,8 --out OUT           # CPU ranks
  /usr/bin/python3 scaling/run.py cubes-weak --backend cuda --ranks 1,2 --out OUT  # 1 rank/GPU
  /usr/bin/python3 scaling/run.py dambreak-balance --variants balanced,static --out OUT
  /usr/bin/python3 scaling/run.py cubes-weak --ranks 64 --launcher srun --out OUT  # in Slurm
  /usr/bin/python3 scaling/run.py cubes-weak --ranks 1 --launcher none --out OUT   # no MPI

Launch (stated in every record under `launch`):
  mpirun   -np N, --map-by core --bind-to core with 1 thread per rank (OMP_NUM_THREADS=1,
           OMP_PROC_BIND=close, OMP_PLACES=cores); --map-by slot:PE=T --bind-to core with T
           threads per rank (cuda: T = min(cores / GPUs, 8), the solver's default for a GPU
           rank: more idle threads spin, and a VM's host steals their cores); when N x T exceeds the cores:
           --oversubscribe --bind-to none (said so in the record). --allow-run-as-root when
           root. cuda: one rank per GPU, the stepper picks GPU (rank % GPUs on the node).
  srun     inside a Slurm allocation: srun -n N --cpus-per-task=T --cpu-bind=cores
           [--gpus-per-task=1] (see scaling/slurm/).
  none     the binary directly (one rank; the single-rank calibration runs).
  copies   weak sweeps only, the node's baseline: N independent one-rank runs of the 1-rank
           scene at once, each pinned to its own core (taskset), no MPI. Their time per step
           (the slowest copy) over the 1-rank time is what sharing the node costs (memory
           bandwidth, caches, clock) before any communication; records carry variant
           "copies". report.py splits the weak efficiency into this node factor and the
           decomposition's own: E(N) = t(1)/t(N) = [t(1)/t_copies(N)] x [t_copies(N)/t(N)].

Time per step. `step_s` = sum over the top-level phases of summary.json (per-rank mean
`parallel.phases_mean` when distributed, else `phases`) without "output", / steps: the
stepping loop (elements, integration, contact, sph, halo exchange, and the rebalances and
layout rebuilds during the run: "migration", "balance") without field snapshots and set-up.
The first distribution (every item from its start slice to its owner, the fluid's first
layout) is set-up, `parallel.setup_s`, outside the phases; `step_s_all` adds it (the
balancer comparison uses it, over runs long enough to amortise it). `wall_s` is the whole
process. Weak/strong efficiency (report.py) uses step_s. Records before schema
qdemsph.scaling.run/2 left "migration" and "balance" out of step_s (they mixed the set-up in).

A run on N > 1 ranks whose summary.json has no `parallel.ranks == N` ran N independent
copies (a binary without the distributed stepper): it is recorded as status
"not-distributed" and the sweep stops.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import re
import resource
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
import scenes  # noqa: E402

# A GPU rank's OpenMP threads unless --threads says (the solver's own default for a GPU rank,
# kGpuRankThreads in solver/core/exec_host.hpp; scaling/README.md, "Host threads of a GPU rank").
GPU_RANK_THREADS = 8

SCHEMA = "qdemsph.scaling.run/2"
PHASES = ("elements", "integration", "contact", "sph", "halo", "migration", "balance", "output")


def sh(cmd, timeout=30):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return ""


def revision_of(qdemsph: str) -> str:
    """The revision the binary was built from: QDEMSPH_REVISION, else the REVISION file of the
    pack it comes from (PACK/bin/qdemsph; ci/gpu/pack.sh writes PACK/REVISION), else this
    checkout's. Several packs measured in one call so keep their own revisions."""
    if os.environ.get("QDEMSPH_REVISION"):
        return os.environ["QDEMSPH_REVISION"]
    pack_rev = Path(qdemsph).resolve().parent.parent / "REVISION"
    rev = pack_rev.read_text().strip() if pack_rev.is_file() else ""
    return rev or sh(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"])


def machine_facts(qdemsph: str) -> dict:
    cpu = platform.processor()
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    gpus = [g for g in sh(["nvidia-smi", "--query-gpu=name,memory.total,driver_version", "--format=csv,noheader"]).split("\n") if g]
    topo = sh(["nvidia-smi", "topo", "-m"]) if gpus else ""
    sockets = sh(["bash", "-c", "lscpu | grep -E '^(Socket|NUMA node\\(s\\)|Core\\(s\\) per socket|Thread\\(s\\) per core)'"])
    mem = 0
    try:
        mem = int(next(line.split()[1] for line in open("/proc/meminfo") if line.startswith("MemTotal"))) * 1024
    except (OSError, StopIteration):
        pass
    return {"host": platform.node(), "cpu": cpu, "cores": os.cpu_count(),
            "usable_cores": len(os.sched_getaffinity(0)), "lscpu": sockets, "memory_bytes": mem,
            "gpus": gpus, "gpu_topology": topo, "mpirun": sh(["mpirun", "--version"]).split("\n")[0],
            "qdemsph": sh([qdemsph, "version"]).split("\n")[0],
            "revision": revision_of(qdemsph),
            "kernel": platform.release(), "loadavg_before": list(os.getloadavg())}


def scene_dt(qdemsph: str, scene_path: Path) -> float:
    """The dt the solver would choose (min of the solid and fluid limits), from `qdemsph info`."""
    out = subprocess.run([qdemsph, "info", str(scene_path)], capture_output=True, text=True, check=True).stdout
    solid = re.search(r"^dt\s+([0-9.eE+-]+) s \(stability limit ([0-9.eE+-]+)", out, re.M)
    fluid = re.search(r"^fluid dt\s+([0-9.eE+-]+)", out, re.M)
    has_tets = float(solid.group(2)) > 0 if solid else False
    cands = ([float(solid.group(1))] if has_tets else []) + ([float(fluid.group(1))] if fluid else [])
    if not cands:
        raise RuntimeError(f"no dt in `qdemsph info {scene_path}`:\n{out}")
    return min(cands) * (1 - 1e-3)  # the printed value is rounded: stay below the limit


def launch_command(launcher: str, ranks: int, threads: int, backend: str, cores: int, root: bool,
                   extra: list[str]) -> tuple[list[str], dict, dict]:
    """(argv prefix, environment, launch facts) for `ranks` ranks of `threads` threads."""
    env = {"OMP_NUM_THREADS": str(threads), "OMP_PROC_BIND": "close", "OMP_PLACES": "cores",
           "PMIX_MCA_pcompress_base_silence_warning": "1"}
    facts = {"launcher": launcher, "ranks": ranks, "threads_per_rank": threads, "backend": backend}
    if launcher == "copies":
        facts["binding"] = f"{ranks} independent processes, process k pinned to core k (taskset)"
        return [], env, facts
    if launcher == "none":
        if ranks != 1:
            raise ValueError("--launcher none runs one rank")
        facts["binding"] = "none (one process, OpenMP threads close to cores)"
        return [], env, facts
    if launcher == "srun":
        cmd = ["srun", "-n", str(ranks), f"--cpus-per-task={threads}", "--cpu-bind=cores"]
        if backend == "cuda":
            cmd.append("--gpus-per-task=1")
        facts["binding"] = f"srun --cpu-bind=cores, {threads} cores per rank" + (", 1 GPU per rank" if backend == "cuda" else "")
        return cmd + extra, env, facts
    cmd = ["mpirun", "-np", str(ranks)]
    if root:
        cmd.append("--allow-run-as-root")
    if ranks * threads > cores:
        cmd += ["--oversubscribe", "--bind-to", "none"]
        facts["binding"] = f"none: {ranks} x {threads} threads > {cores} cores (oversubscribed)"
        facts["oversubscribed"] = True
    elif threads == 1:
        cmd += ["--map-by", "core", "--bind-to", "core"]
        facts["binding"] = "one core per rank (--map-by core --bind-to core)"
    else:
        cmd += ["--map-by", f"slot:PE={threads}", "--bind-to", "core"]
        facts["binding"] = f"{threads} consecutive cores per rank (--map-by slot:PE={threads} --bind-to core)"
    for k, v in env.items():
        cmd += ["-x", f"{k}={v}"]
    return cmd + extra, env, facts


NOT_STEP = ("output",)  # not in step_s; step_s_all adds parallel.setup_s


def step_seconds(summary: dict) -> dict:
    par = summary.get("parallel") or {}
    src = par.get("phases_mean") or summary.get("phases") or {}
    top = {k: float(v) for k, v in src.items() if "." not in k}
    steps = max(int(summary.get("steps") or 0), 1)
    loop = sum(v for k, v in top.items() if k not in NOT_STEP)
    setup = float(par.get("setup_s") or 0.0)
    out = {"step_s": loop / steps, "step_s_all": (loop + setup) / steps, "setup_s": setup,
           "phases_per_step": {k: v / steps for k, v in top.items()},
           "phase_source": "parallel.phases_mean" if par.get("phases_mean") else "phases"}
    if par.get("phases_max"):
        out["phases_max_per_step"] = {k: float(v) / steps for k, v in par["phases_max"].items() if "." not in k}
        out["step_s_maxsum"] = sum(v for k, v in out["phases_max_per_step"].items() if k not in NOT_STEP)
    return out


# A rank's own work in parallel.phases_by_rank: the bodies' and the fluid's passes ("sph" there is
# the fluid's without its halo refreshes and layout rebuilds), not the halo, migration, balance or
# output, where a rank also waits for the others.
BUSY = ("elements", "integration", "contact", "sph")


def busy_imbalance(par: dict):
    """max / mean - 1 over the ranks of their busy seconds over the whole run (BUSY, from
    parallel.phases_by_rank); None without per-rank phases. Unlike parallel.imbalance (the bodies'
    last measurement window) it counts the fluid."""
    busy = [sum(float(m.get(k, 0.0)) for k in BUSY) for m in par.get("phases_by_rank") or []]
    mean = sum(busy) / len(busy) if busy else 0.0
    return max(busy) / mean - 1 if mean > 0 else None


def host_usage() -> dict:
    """What the processes this one has waited for used, and the host's CPU steal time (a
    VM's vCPUs waiting for the hypervisor; /proc/stat, Linux only): take one before and one
    after a run, and usage_between() gives the run's share."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    u = {"user_s": ru.ru_utime, "sys_s": ru.ru_stime, "minor_faults": ru.ru_minflt, "major_faults": ru.ru_majflt,
         "voluntary_switches": ru.ru_nvcsw, "involuntary_switches": ru.ru_nivcsw}
    try:
        cpu = Path("/proc/stat").read_text().split("\n", 1)[0].split()
        u["steal_s"] = int(cpu[8]) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        pass
    return u


def usage_between(before: dict, after: dict) -> dict:
    """The run's usage (host_usage after minus before): CPU seconds of its processes in user
    and kernel mode, their page faults (minor: a page first touched or mapped; each costs more
    in a VM) and context switches, and the seconds the host's CPUs were stolen meanwhile (all
    CPUs, not only the run's)."""
    return {k: round(after[k] - before[k], 6) for k in after if k in before}


def make_record(meta, launch, summary, facts, run_wall, status, note="", usage=None) -> dict:
    rec = {"schema": SCHEMA, "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
           "sweep": meta["sweep"], "case": meta["case"], "mode": meta["mode"], "variant": meta.get("variant"),
           "ranks": launch["ranks"], "gpus": launch["ranks"] if launch["backend"] == "cuda" else 0,
           "backend": launch["backend"], "threads_per_rank": launch["threads_per_rank"], "launch": launch,
           "size": {k: meta[k] for k in ("n_tets", "n_vertices", "n_particles", "bodies", "layout")},
           "preset": meta["preset"], "preset_params": meta["preset_params"], "params": meta.get("params") or {},
           "status": status, "note": note,
           "process_wall_s": run_wall, "host_usage": usage, "loadavg_after": list(os.getloadavg()),
           "machine": facts}
    if summary:
        rec["summary"] = {k: summary.get(k) for k in ("wall_s", "steps", "sim_time", "dt", "n_tets", "n_vertices",
                                                       "backend", "threads", "status", "phases", "contact", "fluid")}
        rec["wall_s"] = summary.get("wall_s")
        rec["steps"] = summary.get("steps")
        rec.update(step_seconds(summary))
        par = summary.get("parallel")
        rec["distributed"] = bool(par)
        if par:
            rec["parallel"] = par
            for k in ("imbalance", "imbalance_initial", "halo_bytes_per_step", "migrated_bytes",
                      "fluid_halo_bytes_per_step", "fluid_migrated_bytes", "fluid_rebuilds", "fluid_recuts", "rebalances",
                      "curve"):
                rec[k] = par.get(k)
            rec["busy_imbalance"] = busy_imbalance(par)
        c = summary.get("contact") or {}
        rec["items"] = {"tets": summary.get("n_tets") or 0, "vertices": summary.get("n_vertices") or 0,
                        "particles": ((summary.get("fluid") or {}).get("n_fluid") or 0) + ((summary.get("fluid") or {}).get("n_wall") or 0),
                        "contact_pairs": c.get("pairs") or 0, "contacts": c.get("contacts") or 0,
                        "surface_triangles": c.get("surface_triangles") or 0}
    return rec


def run_copies(n, cmd, rd, env, limit, cores):
    """n copies of `cmd` (its --out replaced by rd/k), copy k pinned to core k; (status, note,
    the slowest copy's summary with "copies_step_s": every copy's step time)."""
    procs = []
    rd.mkdir(parents=True, exist_ok=True)
    pin = shutil.which("taskset") and n <= cores
    for k in range(n):
        c = cmd[:cmd.index("--out") + 1] + [str(rd / str(k))] + cmd[cmd.index("--out") + 2:]
        procs.append(subprocess.Popen((["taskset", "-c", str(k)] if pin else []) + c, env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True))
    t_end = time.time() + limit
    errs = []
    for p in procs:
        try:
            _, err = p.communicate(timeout=max(1.0, t_end - time.time()))
        except subprocess.TimeoutExpired:
            for q in procs:
                q.kill()
            raise
        if p.returncode != 0:
            errs.append(f"exit {p.returncode}: {err[-500:]}")
    if errs:
        return "failed", "; ".join(errs), None
    sums = [json.loads((rd / str(k) / "summary.json").read_text()) for k in range(n)]
    times = [step_seconds(s)["step_s"] for s in sums]
    worst = dict(sums[times.index(max(times))], copies_step_s=times)
    return "ok", "" if pin else "not pinned (no taskset, or more copies than cores)", worst


def params_tag(params: dict) -> str:
    """File-name suffix of a run with overridden preset values ("" for the preset itself)."""
    return "".join(f"_{k}-{v}" for k, v in sorted(params.items()))


def run_sweep(a) -> list[dict]:
    sw = scenes.SWEEPS[a.sweep]
    ranks = [int(x) for x in a.ranks.split(",")] if a.ranks else sw["ranks"]
    variants = a.variants.split(",") if a.variants else sw.get("variants", [None])
    out = Path(a.out).resolve()
    (out / "records").mkdir(parents=True, exist_ok=True)
    work = Path(a.work).resolve() if a.work else out / "runs"
    work.mkdir(parents=True, exist_ok=True)
    qd = str(Path(a.qdemsph).resolve()) if os.sep in a.qdemsph else shutil.which(a.qdemsph) or a.qdemsph
    facts = machine_facts(qd)
    cores = facts["usable_cores"]
    threads = a.threads or (max(1, min(cores // max(ranks), GPU_RANK_THREADS)) if a.backend == "cuda" else 1)
    # dt: once, from the 1-rank scene (weak: the same local geometry at every N; strong: the
    # same scene), fixed for every run of the sweep.
    try:
        params = scenes.parse_params(a.param)
        s0, m0 = scenes.scene_for(a.sweep, 1, a.backend, params=params)
    except (ValueError, KeyError) as e:
        raise SystemExit(f"run.py: {e}") from None
    p0 = work / f"{a.sweep}_{a.backend}_dt.yaml"
    p0.write_text(scenes.dump(s0))
    dt_fixed = scene_dt(qd, p0)
    steps = a.steps or m0["steps"]
    end_time = steps * dt_fixed if steps else m0["end_time"]
    t_start, last = time.time(), 0.0
    records = []
    print(f"# {a.sweep} ({sw['mode']}, {a.backend} preset) ranks {ranks} variants {variants}: dt {dt_fixed:.6g} s, "
          f"end_time {end_time:.6g} s ({round(end_time / dt_fixed)} steps), {threads} thread(s) per rank", flush=True)
    if a.launcher == "copies":
        if sw["mode"] != "weak":
            raise SystemExit("--launcher copies is the baseline of weak sweeps")
        variants = ["copies"]
    for n in ranks:
        for var in variants:
            left = a.budget - (time.time() - t_start) if a.budget else None
            if left is not None and left < 1.3 * last * max(1, a.repeat) + 10:
                print(f"skip N={n} {var or ''}: {left:.0f} s of budget left, the last run took {last:.0f} s", flush=True)
                continue
            copies = var == "copies"
            scene, meta = scenes.scene_for(a.sweep, 1 if copies else n, a.backend, None if copies else var, params)
            if copies:
                meta = dict(meta, variant="copies")
            scene["run"].update({"dt": float(f"{dt_fixed:.9g}"), "end_time": float(f"{end_time:.9g}")})
            if a.backend == "cuda":
                scene["run"]["threads"] = threads
            tag = f"{a.sweep}_{a.backend}_n{n}" + (f"_{var}" if var else "") + params_tag(params)
            sp = work / f"{tag}.yaml"
            sp.write_text(f"# {tag}: generated by scaling/run.py\n" + scenes.dump(scene))
            rd = work / tag
            prefix, env, launch = launch_command(a.launcher, n, threads, a.backend, cores, os.geteuid() == 0,
                                                 shlex.split(a.mpirun_args or ""))
            cmd = prefix + [qd, "run", str(sp), "--out", str(rd), "--quiet"]
            launch["command"] = shlex.join(cmd)
            if copies:
                launch["command"] = f"{n} x taskset -c k {shlex.join(cmd)}/k"
            print(f"$ {launch['command']}", flush=True)
            best, tries = None, []
            for _ in range(max(1, a.repeat)):
                t0, u0 = time.time(), host_usage()
                status, note, summary = "ok", "", None
                shutil.rmtree(rd, ignore_errors=True)
                limit = left if left is not None and left < a.timeout else a.timeout
                try:
                    if copies:
                        status, note, summary = run_copies(n, cmd, rd, dict(os.environ, **env), limit, cores)
                    else:
                        p = subprocess.run(cmd, env=dict(os.environ, **env), capture_output=True, text=True,
                                           timeout=limit)
                        if p.returncode != 0:
                            status, note = "failed", f"exit {p.returncode}: {(p.stderr or p.stdout)[-2000:]}"
                except subprocess.TimeoutExpired:
                    status, note = "timeout", f"killed after {limit:.0f} s (time limit of the run or what was left of the budget)"
                last, usage = time.time() - t0, usage_between(u0, host_usage())
                sj = rd / "summary.json"
                if copies and status == "ok":
                    pass  # run_copies gave the slowest copy's summary
                elif sj.exists():
                    summary = json.loads(sj.read_text())
                    par = summary.get("parallel") or {}
                    if n > 1 and par.get("ranks") != n:
                        status = "not-distributed"
                        note = (f"summary.json has parallel.ranks = {par.get('ranks')}, not {n}: the binary ran {n} "
                                "independent copies (no distributed stepper); nothing measured")
                elif status == "ok":
                    status, note = "failed", "no summary.json"
                if status != "ok":
                    break
                tries.append(step_seconds(summary)["step_s"])
                if best is None or tries[-1] < best[0]:
                    best = (tries[-1], summary, last, usage)
            if status == "ok" and best:
                _, summary, last, usage = best  # the fastest of the repeats (least disturbed by other load)
            rec = make_record(meta, launch, summary, facts, last, status, note, usage)
            if copies:
                rec["ranks"], rec["copies_step_s"] = n, (summary or {}).get("copies_step_s")
            rec["dt"], rec["end_time"] = dt_fixed, end_time
            if len(tries) > 1:
                rec["repeats_step_s"] = tries
            (out / "records" / f"{tag}.json").write_text(json.dumps(rec, indent=1) + "\n")
            records.append(rec)
            if status == "ok":
                par = summary.get("parallel") or {}
                busy = rec.get("busy_imbalance")
                print(f"  N={n:3d} {var or '':9s} {rec['step_s'] * 1e3:9.2f} ms/step  wall {rec['wall_s']:.1f} s  "
                      f"imbalance {par.get('imbalance', float('nan')):.3f}  "
                      f"busy {float('nan') if busy is None else busy:.3f}  halo {par.get('halo_bytes_per_step', 0) / 1e6:.2f} MB/step  "
                      f"fluid halo {par.get('fluid_halo_bytes_per_step', 0) / 1e6:.2f} MB/step  "
                      f"phases/step " + " ".join(f"{k}={v * 1e3:.2f}" for k, v in rec["phases_per_step"].items() if v > 0),
                      flush=True)
            else:
                print(f"  N={n} {status}: {note[:500]}", flush=True)
            if not a.keep:  # field snapshots are large; the record holds what is measured
                for f in ("fields.h5", "fluid.h5", "*/fields.h5", "*/fluid.h5"):
                    for g in rd.glob(f):
                        g.unlink()
            if status == "not-distributed":
                print("  stopping: this binary has no distributed stepper", flush=True)
                return records
            if status != "ok" and not a.keep_going:
                print(f"  stopping the sweep after a run that {status} (larger runs would too; --keep-going runs them)",
                      flush=True)
                return records
    return records


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sweep", choices=list(scenes.SWEEPS))
    ap.add_argument("--ranks", help="comma-separated rank counts (default: the sweep's)")
    ap.add_argument("--backend", default="cpu", choices=["cpu", "cuda"], help="backend and size preset")
    ap.add_argument("--threads", type=int, default=0, help="OpenMP threads per rank (default: 1 for cpu, min(cores/ranks, 8) for cuda)")
    ap.add_argument("--variants", help="e.g. balanced,static (default: the sweep's)")
    ap.add_argument("--launcher", default="mpirun", choices=["mpirun", "srun", "none", "copies"])
    ap.add_argument("--mpirun-args", default="", help="extra launcher arguments (one string)")
    ap.add_argument("--qdemsph", default=os.environ.get("QDEMSPH", str(REPO / "build" / "bin" / "qdemsph")))
    ap.add_argument("--steps", type=int, default=0, help="timed steps (default: the preset's)")
    ap.add_argument("--param", action="append", metavar="KEY=VALUE",
                    help="override a value of the size preset (repeatable), e.g. cubes_per_rank=864: the "
                         "sweep at another size per rank; records and report series carry it")
    ap.add_argument("--timeout", type=float, default=600, help="seconds per run")
    ap.add_argument("--budget", type=float, default=0, help="seconds for the whole sweep (0: none); later runs are skipped")
    ap.add_argument("--out", required=True, help="records go to OUT/records/")
    ap.add_argument("--work", help="scenes and run folders (default OUT/runs)")
    ap.add_argument("--repeat", type=int, default=1, help="run each point R times, keep the fastest (all step times recorded)")
    ap.add_argument("--keep-going", action="store_true", help="go on after a failed or timed-out run")
    ap.add_argument("--keep", action="store_true", help="keep fields.h5 / fluid.h5 of the runs")
    a = ap.parse_args(argv)
    recs = run_sweep(a)
    bad = [r for r in recs if r["status"] != "ok"]
    return 1 if bad and all(r["status"] != "ok" for r in recs) else 0


if __name__ == "__main__":
    sys.exit(main())
