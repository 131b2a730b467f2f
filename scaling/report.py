#!/usr/bin/python3
"""Scaling report: efficiency tables and plots from run records (run.py), with the model's
predictions drawn as such.

  /usr/bin/python3 scaling/report.py RECORDS_DIR_OR_FILES... [--out build/scaling-report]
  (default input: references/benchmarks/scaling/, recursively)

Writes OUT/report.md (tables), OUT/report.html (tables + figures) and OUT/*.png:
  weak_<sweep>_<backend>.png   time per step and efficiency vs ranks (vs 1 rank and vs 8
                               ranks, the report's convention), measured points, model lines
  phases_<sweep>_<backend>.png per-phase time per step (mean over ranks), stacked bars
  strong_<sweep>_<backend>.png speed-up and efficiency of a fixed problem
  balance_<sweep>_<backend>.png balancer on vs static partition (time per step, imbalance)
  prediction_<sweep>.png       the model alone to 512 ranks (a PREDICTION, not a measurement)

Efficiency: weak E(N) = t(N_ref) / t(N); strong E(N) = N_ref t(N_ref) / (N t(N)); t = step_s
(run.py: stepping loop per step, output excluded) of the median run of the series' revision at
each rank count (series()); an E against another revision's t(N_ref) is marked "†". The model
line of a measured series uses per-item costs calibrated from that series' own 1-rank record
and the partition geometry of its scenes (geometry.py); where it differs from the points, the
points are right.

verification/report.py calls `section(out_dir)` and adds the figures and tables to the verify
report when records exist.
"""
from __future__ import annotations

import argparse
import base64
import html
import io
import json
import sys
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
import model  # noqa: E402
from run import SCHEMA  # noqa: E402

RECORDS = REPO / "references" / "benchmarks" / "scaling"
PHASE_ORDER = ["elements", "contact", "sph", "integration", "halo", "migration", "balance", "checks", "output"]


def load_records(paths) -> list[dict]:
    recs = []
    for p in paths:
        p = Path(p)
        files = sorted(p.rglob("*.json")) if p.is_dir() else [p]
        for f in files:
            try:
                r = json.loads(f.read_text())
            except (json.JSONDecodeError, OSError):
                continue
            if isinstance(r, dict) and r.get("schema") == SCHEMA:
                r["_file"] = str(f)
                recs.append(r)
    return recs


def machine_label(r) -> str:
    m = r.get("machine") or {}
    if r.get("backend") == "cuda" and m.get("gpus"):
        return m["gpus"][0].split(",")[0] + f" x{len(m['gpus'])}"
    return f"{m.get('cpu', '?')} ({m.get('usable_cores', '?')} cores)"


def revision(r):
    return (r.get("machine") or {}).get("revision")


def newest_revision(rs):
    """The revision of the newest of runs rs, a build's before an experiment's: a pack with
    changes beside its commit says so with a "+" (run.py: QDEMSPH_REVISION, "d94fa87+exp-..."),
    and a call that runs it against the build interleaves them, either last."""
    built = [r for r in rs if "+" not in (revision(r) or "")]
    return revision(max(built or rs, key=lambda r: r["date"]))


def series(recs):
    """{(sweep, backend, variant, host label, overridden preset values): [records sorted by
    ranks]} of ok runs. The series' revision is the newest run's (newest_revision); a rank
    count that has none of its runs takes its own newest revision. Per rank count: of the runs
    of that revision, the one with the median step time (the faster of the middle two): repeats
    of one build (the interleaved runs of a call) give one row, which a single slow run does
    not decide. The row carries those runs' step times (`step_s_runs`, sorted): their spread is
    the host's and the run's."""
    runs = defaultdict(lambda: defaultdict(list))
    for r in recs:
        if r.get("status") != "ok" or not r.get("step_s"):
            continue
        k = (r["sweep"], r["backend"], r.get("variant") or "", machine_label(r),
             " ".join(f"{p}={v}" for p, v in sorted((r.get("params") or {}).items())))
        runs[k][r["ranks"]].append(r)
    out = {}
    for k, by_ranks in runs.items():
        out[k] = []
        cur = newest_revision([r for rs in by_ranks.values() for r in rs])
        for n in sorted(by_ranks):
            rs = by_ranks[n]
            rev = cur if any(revision(r) == cur for r in rs) else newest_revision(rs)
            same = sorted((r for r in rs if revision(r) == rev), key=lambda r: r["step_s"])
            out[k].append(dict(same[(len(same) - 1) // 2], step_s_runs=[r["step_s"] for r in same]))
    return out


def spread(runs) -> str:
    """The runs' step times for a table cell: "k: min-max" ms, or "1" for a single run."""
    return "1" if len(runs) == 1 else f"{len(runs)}: {min(runs) * 1e3:.2f}-{max(runs) * 1e3:.2f}"


def efficiencies(rs, mode):
    """Table rows of a series (series()): E against 1 and 8 ranks, and a strong series' speed-up
    against its fewest ranks. Where the reference row is of another revision (a rank count the
    series' newest call did not run), `other_ref` names the references: another build's step
    time is this one's baseline only where their one-rank code is the same, which the table
    cannot know, so it marks them."""
    t = {r["ranks"]: r["step_s"] for r in rs}
    rev = {r["ranks"]: revision(r) for r in rs}
    # Contact work a rank: candidate pairs summed over the ranks, per rank, against one rank's.
    pairs = {r["ranks"]: (r.get("items") or {}).get("contact_pairs") or 0 for r in rs}
    rows = []
    for r in rs:
        n = r["ranks"]
        row = {"ranks": n, "step_s": r["step_s"], "runs": r.get("step_s_runs") or [r["step_s"]],
               "revision": rev[n],
               "imbalance": r.get("imbalance"),
               "busy_imbalance": r.get("busy_imbalance"),
               "halo_bytes_per_step": r.get("halo_bytes_per_step"),
               "fluid_halo_bytes_per_step": r.get("fluid_halo_bytes_per_step"), "size": r["size"]}
        row["other_ref"] = [ref for ref in (1, 8) if ref in t and n >= ref and rev[ref] != rev[n]]
        for ref in (1, 8):
            if ref in t and n >= ref:
                row[f"E{ref}"] = t[ref] / t[n] if mode == "weak" else ref * t[ref] / (n * t[n])
        if mode == "strong":
            row["speedup"] = t[min(t)] / t[n]
        if mode == "weak" and pairs.get(1) and pairs[n]:
            row["pairs_ratio"] = pairs[n] / (n * pairs[1])
        rows.append(row)
    return rows


def node_factors(rows, rs, copies):
    """Node factor and the decomposition's own efficiency (rows' "node", "decomp") from N
    independent copies of the 1-rank run on the same machine (run.py --launcher copies; their
    step: "copies_s"): t(1) / t(N copies) and t(N copies) / t(N ranks), where the copies, the
    1-rank run and the N-rank run are of one revision (another revision's baseline would
    divide unlike step times)."""
    cop = {r["ranks"]: r for r in copies}
    one = next((r for r in rs if r["ranks"] == 1), None)
    for row, r in zip(rows, rs):
        c = cop.get(row["ranks"])
        if c and one and revision(c) == revision(one) == revision(r):
            row["copies_s"] = c["step_s"]
            row["node"] = one["step_s"] / c["step_s"]
            row["decomp"] = c["step_s"] / row["step_s"]


def model_line(rs, sweep, backend, ranks):
    """Model prediction for a measured weak series: costs from its 1-rank record, geometry
    from geometry_<sweep>_<backend>.json; None when either is missing."""
    one = next((r for r in rs if r["ranks"] == 1), None)
    gfile = RECORDS / f"geometry_{sweep}_{backend}.json"
    if one is None or not gfile.exists():
        return None
    c = model.costs_from_record(one)
    costs = model.Costs(tet=c.get("tet", 0.0), vertex=c.get("vertex", 0.0), pair=c.get("pair", 0.0),
                        particle=c.get("particle", 0.0), step=c.get("step", 0.0), label="1-rank record")
    geo = json.loads(gfile.read_text())
    net = model.NETWORKS["ipc-ndr" if backend == "cuda" else "cpu-shm"]  # what the stepper does
    rows = [g for g in model.extend_rows(geo["rows"], ranks) if g["ranks"] in ranks]
    opt = model.Options(pairs_per_surface_vertex=c.get("pairs_per_surface_vertex", 0.0),
                        round_trips=model.round_trips(bool((one.get("items") or {}).get("particles"))))
    return model.predict(rows, costs, net, opt), net.name


def _fig_png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return buf.getvalue()


def plots(recs):
    """[(name, title, png bytes)] and markdown tables (tables only without matplotlib)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        plt = None
    figs, md = [], []
    ser = series(recs)
    for (sweep, backend, variant, mach, params), rs in sorted(ser.items()):
        if variant == "copies":  # the node baseline: columns of its weak series (below)
            continue
        mode = rs[0]["mode"]
        rows = efficiencies(rs, mode)
        node_factors(rows, rs, ser.get((sweep, backend, "copies", mach, params), []))
        cop = [row for row in rows if "node" in row]
        ranks = [r["ranks"] for r in rs]
        tag = f"{sweep}_{backend}" + (f"_{variant}" if variant else "") + "".join(f"_{q}" for q in params.split())
        label = f"{backend}{', ' + variant if variant else ''}{', ' + params if params else ''}"
        md.append(f"\n### {sweep} ({mode}, {label}) on {mach}\n")
        if cop:
            md.append("E vs 1 = node x decomposition: *node* = t(1) / t(N copies of the 1-rank run at once, "
                      "one per core), *decomposition* = t(N copies) / t(N ranks).\n")
        if any("pairs_ratio" in r for r in rows):
            md.append("*pairs/rank*: the contact candidate pairs a rank, against the 1-rank run's (above 1 where "
                      "the grown scene gives a body more neighbours, or where two ranks test a pair).\n")
        if any(row["other_ref"] for row in rows):
            md.append("† against the 1- or 8-rank run of another revision (the revision column).\n")
        md.append("| ranks | tets | particles | ms/step | runs: ms/step | E vs 1 | E vs 8 | node | decomposition | imbalance "
                  "| busy imbalance | halo MB/step | fluid halo MB/step | pairs/rank | revision |")
        md.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
        for row in rows:
            f = lambda v, s="{:.3f}": "" if v is None else s.format(v)  # noqa: E731
            mb = lambda v: f(None if v is None else v / 1e6, "{:.2f}")  # noqa: E731
            e = lambda ref: f(row.get(f"E{ref}")) + ("†" if ref in row["other_ref"] else "")  # noqa: E731
            md.append(f"| {row['ranks']} | {row['size']['n_tets']:,} | {row['size']['n_particles']:,} | "
                      f"{row['step_s'] * 1e3:.2f} | {spread(row['runs'])} | {e(1)} | {e(8)} | "
                      f"{f(row.get('node'))} | {f(row.get('decomp'))} | "
                      f"{f(row['imbalance'])} | {f(row.get('busy_imbalance'))} | {mb(row['halo_bytes_per_step'])} | "
                      f"{mb(row.get('fluid_halo_bytes_per_step'))} | {f(row.get('pairs_ratio'))} | "
                      f"{row['revision'] or ''} |")
        # The model's geometry files are of the presets' sizes.
        pred = (model_line(rs, sweep, backend, ranks) if mode == "weak" and not variant and not params and len(rs) > 1
                else None)
        if pred:
            md.append(f"\nModel PREDICTION for these runs (costs from the 1-rank record, network {pred[1]}): "
                      + ", ".join(f"N={p['ranks']}: E={p.get('efficiency_vs_1', float('nan')):.3f}" for p in pred[0]))
        if plt is None or len(rs) < 2:  # a single rank count: the table says it all
            continue
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
        ax[0].errorbar(ranks, [r["step_s"] * 1e3 for r in rs],
                       yerr=[[(r["step_s"] - min(r["step_s_runs"])) * 1e3 for r in rs],
                             [(max(r["step_s_runs"]) - r["step_s"]) * 1e3 for r in rs]],
                       fmt="o-", capsize=3, label="measured (median run; bars: the runs' range)")
        ax[0].set_xscale("log", base=2)
        ax[0].set_xlabel("ranks" + (" (GPUs)" if backend == "cuda" else " (cores)"))
        ax[0].set_ylabel("time per step [ms]")
        if any("E1" in r for r in rows):
            ax[1].plot(ranks, [r.get("E1", float("nan")) for r in rows], "o-", label="measured, vs 1 rank")
        elif not any("E8" in r for r in rows):  # e.g. the balancer's 2 and 4 GPUs: vs the fewest
            n0, t0 = rows[0]["ranks"], rows[0]["step_s"]
            ax[1].plot(ranks, [t0 / r["step_s"] * (1 if mode == "weak" else n0 / r["ranks"]) for r in rows],
                       "o-", label=f"measured, vs {n0} ranks")
        if any("E8" in r for r in rows):
            ax[1].plot([r["ranks"] for r in rows if "E8" in r], [r["E8"] for r in rows if "E8" in r], "s-",
                       label="measured, vs 8 ranks")
        if any("decomp" in r for r in rows):
            ax[1].plot([r["ranks"] for r in rows if "decomp" in r], [r["decomp"] for r in rows if "decomp" in r],
                       "^-", label="decomposition only (vs N independent copies)")
            ax[1].plot([r["ranks"] for r in rows if "node" in r], [r["node"] for r in rows if "node" in r], "v:",
                       color="0.4", label="node: N independent copies vs 1")
            ax[0].plot([r["ranks"] for r in cop], [r["copies_s"] * 1e3 for r in cop], "v:", color="0.4",
                       label="N independent copies of the 1-rank run")
        if pred:
            ax[0].plot([p["ranks"] for p in pred[0]], [p["step_s"] * 1e3 for p in pred[0]], "--", color="0.5",
                       label=f"model prediction ({pred[1]})")
            ax[1].plot([p["ranks"] for p in pred[0]], [p.get("efficiency_vs_1") for p in pred[0]], "--", color="0.5",
                       label=f"model prediction ({pred[1]})")
        ax[1].axhline(0.9, color="tab:red", lw=0.8, ls=":", label="90 % (goal)")
        ax[1].set_xscale("log", base=2)
        ax[1].set_ylim(0, 1.15)
        ax[1].set_xlabel(ax[0].get_xlabel())
        ax[1].set_ylabel(f"{mode} efficiency")
        for a in ax:
            a.grid(alpha=0.3)
            a.legend(fontsize=8)
        fig.suptitle(f"{sweep} ({mode}, {label}): {mach}, {rs[-1]['date'][:10]}", fontsize=10)
        fig.tight_layout()
        figs.append((f"{mode}_{tag}", f"{sweep} {mode} efficiency", _fig_png(fig)))
        plt.close(fig)
        # per-phase stacked bars
        fig, ax = plt.subplots(figsize=(7.5, 4.2))
        bottom = [0.0] * len(rs)
        phases = [p for p in PHASE_ORDER if any(r["phases_per_step"].get(p, 0) > 0 for r in rs)]
        xs = [str(n) for n in ranks]
        for p in phases:
            v = [r["phases_per_step"].get(p, 0.0) * 1e3 for r in rs]
            ax.bar(xs, v, bottom=bottom, label=p)
            bottom = [b + x for b, x in zip(bottom, v)]
        ax.set_xlabel("ranks")
        ax.set_ylabel("ms per step (mean over ranks)")
        ax.set_title(f"{sweep} ({label}) phases: {mach}", fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3, axis="y")
        fig.tight_layout()
        figs.append((f"phases_{tag}", f"{sweep} phases", _fig_png(fig)))
        plt.close(fig)
    # balancer on vs off
    bal = defaultdict(dict)
    for (sweep, backend, variant, mach, params), rs in ser.items():
        if variant and not params:
            bal[(sweep, backend, mach)][variant] = {r["ranks"]: r for r in rs}
    for (sweep, backend, mach), vs in sorted(bal.items()):
        if not {"balanced", "static"} <= set(vs):
            continue
        ns = sorted(set(vs["balanced"]) & set(vs["static"]))
        md.append(f"\n### {sweep}: load balancer on vs static partition ({backend}, {mach})\n")
        md.append("Time per step with (re)partitioning and migration included (step_s_all).\n")
        md.append("| ranks | balanced ms/step | static ms/step | gain | imbalance balanced | imbalance static | rebalances "
                  "| fluid re-cuts | migrated MB | fluid migrated MB |")
        md.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for n in ns:
            b, s = vs["balanced"][n], vs["static"][n]
            tb, ts = b.get("step_s_all", b["step_s"]), s.get("step_s_all", s["step_s"])
            md.append(f"| {n} | {tb * 1e3:.2f} | {ts * 1e3:.2f} | {ts / tb:.2f}x | "
                      f"{b.get('imbalance') or 0:.3f} | {s.get('imbalance') or 0:.3f} | {b.get('rebalances')} | "
                      f"{'-' if b.get('fluid_recuts') is None else b['fluid_recuts']} | {(b.get('migrated_bytes') or 0) / 1e6:.1f} | {(b.get('fluid_migrated_bytes') or 0) / 1e6:.1f} |")
        if plt is None:
            continue
        fig, ax = plt.subplots(figsize=(6.5, 4))
        w = 0.38
        sa = lambda r: r.get("step_s_all", r["step_s"]) * 1e3  # noqa: E731
        ax.bar([i - w / 2 for i in range(len(ns))], [sa(vs["balanced"][n]) for n in ns], w, label="balancer on")
        ax.bar([i + w / 2 for i in range(len(ns))], [sa(vs["static"][n]) for n in ns], w, label="static partition")
        ax.set_xticks(range(len(ns)), [str(n) for n in ns])
        ax.set_xlabel("ranks")
        ax.set_ylabel("time per step incl. migration [ms]")
        ax.set_title(f"{sweep} ({backend}): balancer on vs off, {mach}", fontsize=10)
        ax.legend(fontsize=8)
        fig.tight_layout()
        figs.append((f"balance_{sweep}_{backend}", f"{sweep} balancer", _fig_png(fig)))
        plt.close(fig)
    return figs, md


def prediction_plots():
    """The model alone, 1 to 512 ranks, for every geometry record with a named cost set."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figs, md = [], []
    cost_doc = json.loads((HERE / "costs.json").read_text())
    # (network, overlap, ghost pair weight k): today's stepper (device-resident halos on a node,
    # k measured (model.Options), no overlap), contact pairs evaluated once (k = 0), and GPU-resident halos
    # between nodes too (CUDA-aware MPI) with full overlap. In-run rebuilds are not in these
    # (scaling/README.md: measured, added by --rebuild-ms-per-step).
    k = model.Options().ghost_pair_weight
    plan = [("cuda", "h200-05319f8", [("ipc-ndr", 0.0, k), ("ipc-ndr", 0.0, 0.0), ("cuda-aware-ndr", 1.0, 0.0)]),
            ("cpu", "cpu-core-devvm", [("cpu-shm", 0.0, k), ("cpu-shm", 0.0, 0.0), ("tsubame25", 0.0, 0.0)])]
    ranks = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]
    for gfile in sorted(RECORDS.glob("geometry_*.json")):
        geo = json.loads(gfile.read_text())
        backend = geo.get("backend_preset")
        for be, cname, lines in plan:
            if be != backend or cname not in cost_doc["costs"]:
                continue
            costs = model.load_costs(cname)
            ppv = cost_doc.get("pairs_per_surface_vertex", {}).get(geo["sweep"], 0.0)
            rows = [g for g in model.extend_rows(geo["rows"], ranks) if g["ranks"] in ranks]
            fig, ax = plt.subplots(figsize=(7, 4.2))
            md.append(f"\n### PREDICTION: {geo['sweep']} ({backend} preset), costs '{cname}'\n")
            md.append("| network, overlap, ghost pair weight k | " + " | ".join(f"N={p['ranks']}" for p in rows) + " | E(512) vs 8 |")
            md.append("|---|" + "---:|" * (len(rows) + 1))
            for net, ov, k in lines:
                pred = model.predict(rows, costs, model.NETWORKS[net],
                                     model.Options(pairs_per_surface_vertex=ppv, overlap=ov, ghost_pair_weight=k,
                                                   round_trips=model.geometry_round_trips(geo)))
                lab = f"{net}, overlap {ov:g}, k {k:g}"
                ax.plot([p["ranks"] for p in pred], [p["efficiency_vs_1"] for p in pred], "o-", ms=3, label=lab)
                e8 = pred[-1].get("efficiency_vs_8")
                md.append(f"| {lab} | " + " | ".join(f"{p['efficiency_vs_1']:.3f}" + ("*" if p["extrapolated"] else "")
                                                   for p in pred) + f" | {'' if e8 is None else f'{e8:.3f}'} |")
            md.append("\n(* beyond the largest computed rank count: the slowest of the computed rows with N >= 16)")
            ax.axhline(0.9, color="tab:red", lw=0.8, ls=":")
            ax.set_xscale("log", base=2)
            ax.set_ylim(0, 1.05)
            ax.set_xlabel("ranks (GPUs)" if backend == "cuda" else "ranks (cores)")
            ax.set_ylabel("weak efficiency vs 1 rank")
            ax.set_title(f"PREDICTION (model): {geo['sweep']}, {backend} preset, costs {cname}", fontsize=10)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
            fig.tight_layout()
            figs.append((f"prediction_{geo['sweep']}_{backend}", "prediction", _fig_png(fig)))
            plt.close(fig)
    return figs, md


def section(extra_dirs=()) -> tuple[dict, str]:
    """For verification/report.py: ({figure id: base64 png}, html) of the measured records
    (references/benchmarks/scaling plus extra_dirs); ({}, "") when there are none."""
    recs = load_records([RECORDS, *[d for d in extra_dirs if Path(d).exists()]])
    if not recs:
        return {}, ""
    figs, md = plots(recs)
    b64 = {f"scaling_{name}": base64.b64encode(png).decode("ascii") for name, _, png in figs}
    h = ["<h2>Scaling (measured; model lines are predictions)</h2>", _md_table_html(md)]
    return b64, "\n".join(h)


def _md_table_html(md_lines) -> str:
    out, in_table = [], False
    for ln in md_lines:
        if ln.startswith("|"):
            cells = [c.strip() for c in ln.strip("|").split("|")]
            if set("".join(cells)) <= set("-:"):
                continue
            if not in_table:
                out.append("<table>")
                in_table = True
                out.append("<tr>" + "".join(f"<th>{html.escape(c)}</th>" for c in cells) + "</tr>")
            else:
                out.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + "</tr>")
        else:
            if in_table:
                out.append("</table>")
                in_table = False
            t = ln.strip()
            if t.startswith("### "):
                out.append(f"<h3>{html.escape(t[4:])}</h3>")
            elif t:
                out.append(f"<p>{html.escape(t)}</p>")
    if in_table:
        out.append("</table>")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("inputs", nargs="*", default=[str(RECORDS)])
    ap.add_argument("--out", default=str(REPO / "build" / "scaling-report"))
    ap.add_argument("--no-prediction", action="store_true")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    recs = load_records(a.inputs)
    figs, md = plots(recs) if recs else ([], [])
    bad = [r for r in recs if r.get("status") != "ok"]
    if not a.no_prediction:
        pf, pm = prediction_plots()
        figs += pf
        md += ["\n## Model predictions (not measurements)",
               "\nEfficiency against 1 rank (model.py; geometry from geometry_*.json, costs from costs.json). "
               f"k: candidate contact pairs of a ghost surface vertex per owned one ({model.Options().ghost_pair_weight:g} "
               "measured on the stepper at d32fc91, scaling/model.py; 0: each pair once). Assumed, not measured: "
               "the network parameters (model.NETWORKS), and the SPH halo bytes (the distributed fluid does not record them yet)."] + pm
    head = ["# qdemsph scaling report", "", f"{len(recs)} run records ({len(bad)} not ok) from "
            + ", ".join(a.inputs), ""]
    for r in bad:
        head.append(f"- {r['sweep']} {r['backend']} N={r['ranks']}: {r['status']}: {r.get('note', '')[:200]}")
    (out / "report.md").write_text("\n".join(head + md) + "\n")
    for name, _, png in figs:
        (out / f"{name}.png").write_bytes(png)
    body = _md_table_html(head + md) + "".join(
        f"<img alt='{html.escape(n)}' style='max-width:48%' src='data:image/png;base64,{base64.b64encode(p).decode()}'>"
        for n, _, p in figs)
    (out / "report.html").write_text(f"<!doctype html><html><head><meta charset='utf-8'><title>qdemsph scaling</title>"
                                     f"<style>table{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;"
                                     f"padding:2px 6px}}</style></head><body>{body}</body></html>")
    print(f"{out / 'report.md'}: {len(recs)} records, {len(figs)} figures")
    return 0


if __name__ == "__main__":
    sys.exit(main())
