"""The committed GPU session records (references/benchmarks/gpu/, written by
ci/gpu_session.sh on a GPU machine) in the report: throughput against size for the element
step, the contact stage and the SPH step (GPU and CPU), the GPU-vs-CPU differences, and the
27-cube stack run on the GPU for 1 s, whose settling criteria (the contact_stack case's) are
checked here. No solver run: the records are another machine's. See README.md."""
import json
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
GPU = REPO / "references/benchmarks/gpu"
sys.path.insert(0, str(REPO / "verification/cases/contact_stack"))
from stack_metrics import D_DEM  # noqa: E402


def sessions():
    return sorted(GPU.glob("*_session.json"))


def tag(path, suffix):
    return path.name[: -len(suffix)]


def test_gpu_records(checks):
    recs = sessions()
    if not recs:
        pytest.skip("no GPU session records in references/benchmarks/gpu")
    docs = {path: json.loads(path.read_text()) for path in recs}
    latest = max(recs, key=lambda p: docs[p].get("machine", {}).get("date_utc", ""))
    for path in recs:
        s = docs[path]
        t = tag(path, "_session.json")
        for b in ("gpu", "cpu"):
            r = s.get("bench", {}).get(b)
            if r:
                runs = sorted(list(r.get("runs", [])) + ([r["largest"]] if "largest" in r else []),
                              key=lambda x: x["n_tets"])
                checks.series("gpu_tets", f"{t} {b}", [x["n_tets"] for x in runs],
                              [x["tet_updates_per_s"] for x in runs], style="line", xscale="log", yscale="log",
                              title="Element + integration step (recorded)", xlabel="tets",
                              ylabel="tet-updates / s", note=f"from {path.relative_to(REPO)}")
        cb = s.get("contact_bench") or {}
        for b in ("cuda", "cpu"):
            for n in sorted({x["steps"] for x in cb.get("runs", []) if x.get("backend") == b and "failed" not in x}):
                runs = sorted((x for x in cb["runs"] if x.get("backend") == b and x.get("steps") == n
                               and "failed" not in x), key=lambda x: x["tets"])
                checks.series("gpu_contact", f"{t} {b} ({n} steps)", [x["tets"] for x in runs],
                              [x["surface_pairs_per_s"] for x in runs], style="line", xscale="log", yscale="log",
                              title="Contact stage on grids of the report's cubes (recorded)", xlabel="tets",
                              ylabel="candidate surface-triangle pairs / s")
                for x in runs:
                    checks.info(f"{t}.contact.{b}.{x['cubes']}cubes.{n}steps.pairs_per_s", x["surface_pairs_per_s"],
                                unit="1/s", backend=b)
        sb = s.get("sph_bench") or {}
        for b in ("cuda", "cpu"):
            runs = sorted((x for x in sb.get("runs", []) if x.get("backend") == b), key=lambda x: x["particles"])
            if runs:
                checks.series("gpu_sph", f"{t} {b}", [x["particles"] for x in runs],
                              [x["particle_steps_per_s"] for x in runs], style="line", xscale="log", yscale="log",
                              title="SPH step (recorded)", xlabel="particles", ylabel="particle-steps / s")
        d = s.get("cuda_vs_cpu_stages") or {}
        if d and path == latest:  # the latest session's comparisons (older ones: their records)
            names = sorted(d)
            checks.series("gpu_vs_cpu", t, list(range(len(names))), [max(d[k], 1e-17) for k in names],
                          style="points", yscale="log", labels=names, title="GPU vs CPU: max relative difference",
                          xlabel="comparison (labels)", ylabel="max relative difference")
    for path in sorted(GPU.glob("*_stack27.json")):
        r = json.loads(path.read_text())
        t = tag(path, "_stack27.json")
        sr = r.get("series", {})
        if sr:
            checks.series("gpu_stack27", f"{t} kinetic", sr["time"], sr["kinetic"], style="line",
                          title="27-cube stack on the GPU (recorded)", xlabel="t (s)", ylabel="energy (J)")
            if "contact_dissipated" in sr:
                checks.series("gpu_stack27", f"{t} contact dissipated", sr["time"], sr["contact_dissipated"],
                              style="line")
        m = r["metrics"]
        full = (r.get("sim_time") or 0) >= 1.0 - 1e-6
        kind = "max" if full and r.get("status") == "completed" else "info"
        checks.check(f"{t}.stack27.ke_end_over_peak", m["ke_end_over_peak"], kind=kind,
                     tolerance=0.5 if kind == "max" else None, unit="-", backend=r.get("backend"),
                     wall_s=r.get("wall_s"), note="recorded GPU run of the 27-cube stack")
        checks.check(f"{t}.stack27.lateral_drift", m["lateral_drift"], kind=kind,
                     tolerance=D_DEM if kind == "max" else None, unit="m", backend=r.get("backend"))
        checks.check(f"{t}.stack27.max_overlap", m["max_overlap"], kind=kind,
                     tolerance=2 * D_DEM if kind == "max" else None, unit="m", backend=r.get("backend"))
        checks.info(f"{t}.stack27.wall", r.get("wall_s"), unit="s", backend=r.get("backend"))
    checks.require()
