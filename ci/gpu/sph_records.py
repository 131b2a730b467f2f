#!/usr/bin/env python3
"""Merge a GPU session's SPH benchmark records (scaling/sph_bench.py: sph_gpu.json,
sph_cpu.json, sph_gpu_large.json in WORK) into one record, adding the largest particle count
that fits in the GPU's free memory at the measured bytes per particle.

  ci/gpu/sph_records.py WORK OUT.json"""
import json
import os
import sys

work, out = sys.argv[1], sys.argv[2]
rec = {"benchmark": "sph_step", "runs": []}
for name in ("sph_gpu.json", "sph_cpu.json", "sph_gpu_large.json"):
    p = os.path.join(work, name)
    if os.path.exists(p):
        r = json.load(open(p))
        rec.setdefault("machine", r.get("machine"))
        rec.setdefault("note", r.get("note"))
        rec["date"] = r.get("date")
        rec["runs"] += r.get("runs", [])
m = os.path.join(work, "machine.json")
free = json.load(open(m)).get("gpu_free_bytes", 0) if os.path.exists(m) else 0
gpu = [r for r in rec["runs"] if r.get("backend") == "cuda" and r.get("bytes_per_particle")]
if gpu and free:
    bpp = max(r["bytes_per_particle"] for r in gpu)
    rec["largest_by_memory"] = {"gpu_free_bytes": free, "bytes_per_particle": bpp,
                                "particles": free / bpp,
                                "method": "free GPU memory (nvidia-smi at the session start) / the largest "
                                          "measured bytes per particle (the stage's buffers)"}
json.dump(rec, open(out, "w"), indent=1)
for r in rec["runs"]:
    print("SPH_BENCH " + json.dumps({k: r.get(k) for k in ("backend", "particles", "steps", "particle_steps_per_s",
                                                          "bytes_per_particle")}))
if "largest_by_memory" in rec:
    print(f"SPH largest by memory: {rec['largest_by_memory']['particles']:.3e} particles")
