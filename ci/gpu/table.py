#!/usr/bin/env python3
"""Collect a GPU session's records in OUTDIR into OUTDIR/session.json and print the table."""
import json, os, re, sys

out = sys.argv[1]
S = {"machine": {}, "unit": {}, "cuda_vs_cpu_stages": {}, "scenes": [], "memcheck": {}, "bench": {}}


def load(name):
    p = os.path.join(out, name)
    return json.load(open(p)) if os.path.exists(p) else None


m = load("machine.json")
if m:
    S["machine"] = m
log = os.path.join(out, "session.log")
text = open(log, errors="replace").read() if os.path.exists(log) else ""
for name, v in re.findall(r"\[cuda-vs-cpu\] (\S+) max_rel=(\S+)", text):
    S["cuda_vs_cpu_stages"][name] = float(v)
u = load("unit_cuda.json")
if u:
    S["unit"]["cuda"] = {k: u.get(k) for k in ("tests", "failures", "disabled", "errors", "time")}
mm = re.search(r"UNIT_ALL rc=(\d+) (.*)", text)
if mm:
    S["unit"]["all"] = {"rc": int(mm.group(1)), "summary": mm.group(2)}
for line in text.splitlines():
    if line.startswith("COMPARE "):
        S["scenes"].append(json.loads(line[8:]))
mc = re.search(r"MEMCHECK (\S+) rc=(\d+) (.*)", text)
for mc in re.finditer(r"MEMCHECK (\S+) rc=(\d+) (.*)", text):
    S["memcheck"][mc.group(1)] = {"rc": int(mc.group(2)), "summary": mc.group(3)}
for b in ("gpu", "cpu"):
    r = load(f"bench_{b}.json")
    if r:
        S["bench"][b] = r
json.dump(S, open(os.path.join(out, "session.json"), "w"), indent=2)

print("\n==== qdemsph GPU session ====")
print("machine:", S["machine"].get("gpu", "?"), "|", S["machine"].get("cpu", "?"))
if "cuda" in S["unit"]:
    c = S["unit"]["cuda"]
    print(f"unit tests (Cuda.*): {c['tests']} tests, {c['failures']} failures")
if "all" in S["unit"]:
    print(f"unit tests (all but gmsh): rc {S['unit']['all']['rc']} {S['unit']['all']['summary']}")
if S["cuda_vs_cpu_stages"]:
    print("GPU vs CPU per stage (max relative difference):")
    for k, v in S["cuda_vs_cpu_stages"].items():
        print(f"  {k:<32} {v:.2e}")
for s in S["scenes"]:
    keys = [k for k in s if k.endswith("_max_rel")]
    print(f"scene {s['scene']:<22} status {s['status']} steps {s['steps']} " +
          " ".join(f"{k[:-8]} {s[k]:.1e}" for k in keys))
for k, v in S["memcheck"].items():
    print(f"memcheck {k}: rc {v['rc']} {v['summary']}")
print(f"{'backend':<6} {'size':<8} {'tets':>12} {'tet-upd/s':>11} {'ms/step':>9} {'B/tet-step':>10} "
      f"{'GB/s':>7} {'of copy':>8} {'B/tet':>6}")
for b in ("gpu", "cpu"):
    r = S["bench"].get(b)
    if not r:
        print(f"{b}: no benchmark record")
        continue
    runs = list(r.get("runs", [])) + ([r["largest"]] if "largest" in r else [])
    for x in runs:
        mem = x.get("gpu_bytes_per_tet", x["state_bytes_per_tet"])
        print(f"{b:<6} {x['label']:<8} {x['n_tets']:>12} {x['tet_updates_per_s']:>11.3e} "
              f"{1e3 * x['step_s']:>9.3f} {x['bytes_per_tet_step']:>10.0f} "
              f"{x['achieved_bandwidth_Bps'] * 1e-9:>7.1f} {100 * x['bandwidth_fraction']:>7.1f}% {mem:>6.0f}")
    print(f"  {b} copy bandwidth {r['copy_bandwidth_Bps'] * 1e-9:.1f} GB/s ({r['copy_bandwidth_method']})")
    if "largest_sizing" in r:
        l = r["largest_sizing"]
        print(f"  largest by memory: {l['max_tets_by_memory']:.3e} tets at {l['state_bytes_per_tet']:.0f} B/tet")
