#!/usr/bin/env python3
"""Collect a GPU session's records into OUTDIR/session.json and print the table.

  ci/gpu/table.py OUTDIR [WORKDIR]     (WORKDIR: the session's scratch, holding machine.json)
"""
import json, os, re, sys

out = sys.argv[1]
work = sys.argv[2] if len(sys.argv) > 2 else out
S = {"machine": {}, "unit": {}, "cuda_vs_cpu_stages": {}, "cuda_vs_cpu_lines": [], "scenes": [],
     "memcheck": {}, "stack27": None, "bench": {}, "contact_bench": None, "sph_bench": None,
     "skipped": []}


def load(name, folder=out):
    p = os.path.join(folder, name)
    return json.load(open(p)) if os.path.exists(p) else None


S["machine"] = load("machine.json", work) or load("machine.json") or {}
log = os.path.join(out, "session.log")
text = open(log, errors="replace").read() if os.path.exists(log) else ""
for name, v in re.findall(r"\[cuda-vs-cpu\] (\S+) max_rel=(\S+)", text):
    S["cuda_vs_cpu_stages"][name] = float(v)
S["cuda_vs_cpu_lines"] = [l for l in re.findall(r"\[cuda-vs-cpu\] (.*)", text) if "max_rel=" not in l]
u = load("unit_cuda.json")
if u:
    S["unit"]["cuda"] = {k: u.get(k) for k in ("tests", "failures", "disabled", "errors", "time")}
    S["unit"]["cuda"]["skipped"] = sum(t.get("result") == "SKIPPED" for s in u.get("testsuites", [])
                                       for t in s.get("testsuite", []))
    S["unit"]["cuda"]["failed_tests"] = [f"{s['name']}.{t['name']}" for s in u.get("testsuites", [])
                                         for t in s.get("testsuite", []) if t.get("failures")]
mm = re.search(r"UNIT_ALL rc=(\d+) (.*)", text)
if mm:
    S["unit"]["all"] = {"rc": int(mm.group(1)), "summary": mm.group(2)}
for line in text.splitlines():
    if line.startswith("COMPARE "):
        try:
            S["scenes"].append(json.loads(line[8:]))
        except json.JSONDecodeError:
            S["scenes"].append({"scene": "?", "status": line[8:]})
    if line.startswith("SKIPPED "):
        S["skipped"].append(line[8:])
for mc in re.finditer(r"MEMCHECK (\S+) rc=(\d+) (.*)", text):
    S["memcheck"][mc.group(1)] = {"rc": int(mc.group(2)), "summary": mc.group(3)}
S["stack27"] = load("stack27.json")
if S["stack27"]:
    S["stack27"] = {k: v for k, v in S["stack27"].items() if k != "series"}  # series: in stack27.json
for b in ("gpu", "cpu"):
    r = load(f"bench_{b}.json")
    if r:
        S["bench"][b] = r
S["contact_bench"] = load("contact_bench.json")
S["sph_bench"] = load("sph_bench.json")
json.dump(S, open(os.path.join(out, "session.json"), "w"), indent=2)


def e(x, f=".3e"):
    return format(x, f) if isinstance(x, (int, float)) else str(x)


print("\n==== qdemsph GPU session ====")
print("machine:", S["machine"].get("gpu", "?"), "|", S["machine"].get("cpu", "?"), "x",
      S["machine"].get("cpu_threads", "?"))
if "cuda" in S["unit"]:
    c = S["unit"]["cuda"]
    print(f"unit tests (Cuda.*): {c['tests']} tests, {c['failures']} failures, {c['skipped']} skipped"
          + (f" FAILED: {', '.join(c['failed_tests'])}" if c["failed_tests"] else ""))
if "all" in S["unit"]:
    print(f"unit tests (all but gmsh): rc {S['unit']['all']['rc']} {S['unit']['all']['summary']}")
if S["cuda_vs_cpu_stages"]:
    print("GPU vs CPU in the unit tests (max relative difference):")
    for k, v in S["cuda_vs_cpu_stages"].items():
        print(f"  {k:<40} {v:.2e}")
    for l in S["cuda_vs_cpu_lines"]:
        print(f"  {l}")
for s in S["scenes"]:
    keys = [k for k in s if k.endswith("_max_rel")]
    cc = s.get("contact_counts")
    cc = " counts " + ("equal" if all(a == b for a, b in cc.values()) else f"DIFFER {cc}") if cc else ""
    print(f"scene {s.get('scene', '?'):<20} {s.get('status')} steps {s.get('steps')} " +
          " ".join(f"{k[:-8]} {s[k]:.1e}" for k in keys) + cc)
for k, v in S["memcheck"].items():
    print(f"memcheck {k}: rc {v['rc']} {v['summary']}")
st = S["stack27"]
if st:
    m = st["metrics"]
    print(f"stack27 ({st['backend']}, {st['n_tets']} tets): {st['status']} t = {e(st['sim_time'], '.3f')} s in "
          f"{st['steps']} steps, wall {e(st['wall_s'], '.1f')} s; KE end/peak {m['ke_end_over_peak']:.2e}, "
          f"lateral drift {m['lateral_drift']:.2e} m (D_DEM {st['d_dem']}), max overlap {m['max_overlap']:.2e} m, "
          f"settlement {m['vertical_settlement']:.2e} m; pass {all(st['pass'].values())}")
    c = st.get("cpu_run")
    if c:
        m = c["metrics"]
        print(f"stack27 (cpu, {c['n_tets']} tets): {c['status']} t = {e(c['sim_time'], '.3f')} s in {c['steps']} steps, "
              f"wall {e(c['wall_s'], '.1f')} s; KE end/peak {m['ke_end_over_peak']:.2e}, lateral drift "
              f"{m['lateral_drift']:.2e} m, max overlap {m['max_overlap']:.2e} m, settlement "
              f"{m['vertical_settlement']:.2e} m; pass {all(c['pass'].values())}")
cb = S["contact_bench"]
if cb:
    print(f"{'contact':<7} {'cubes':>5} {'tets':>9} {'steps':>5} {'pairs':>9} {'contacts':>8} "
          f"{'pairs/s':>10} {'contacts/s':>10} {'tet-upd/s':>10} {'ms/step':>8}")
    for r in cb["runs"]:
        if "failed" in r:
            print(f"{r['backend']:<7} {r['cubes']:>5} FAILED rc {r['failed']}")
            continue
        print(f"{r['backend']:<7} {r['cubes']:>5} {r['tets']:>9} {r['steps']:>5} {r['candidate_pairs']:>9} "
              f"{r['contacts']:>8} {e(r['surface_pairs_per_s']):>10} {e(r['contacts_per_s']):>10} "
              f"{e(r['tet_updates_per_s']):>10} {1e3 * r['step_s']:>8.2f}")
sb = S["sph_bench"]
if sb:
    print(f"{'sph':<7} {'particles':>10} {'steps':>5} {'p-steps/s':>10} {'B/particle':>10}")
    for r in sb["runs"]:
        print(f"{r['backend']:<7} {r['particles']:>10} {r['steps']:>5} {e(r['particle_steps_per_s']):>10} "
              f"{r['bytes_per_particle']:>10.0f}")
    if "largest_by_memory" in sb:
        print(f"  sph largest by memory: {sb['largest_by_memory']['particles']:.3e} particles")
print(f"{'tets':<6} {'size':<8} {'tets':>12} {'tet-upd/s':>11} {'ms/step':>9} {'B/tet-step':>10} "
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
for s in S["skipped"]:
    print(f"skipped: {s}")
