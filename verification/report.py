#!/usr/bin/python3
"""Build build/verify/report.html from a verification run and compare it with the baseline.

  /usr/bin/python3 verification/report.py [--out build/verify] [--baseline references/baseline.json]
  /usr/bin/python3 verification/report.py --accept      # make this run the new baseline

Reads <out>/summary.json (records) and <out>/session.json (machine, tier, plot series) written
by the pytest harness, plus any <out>/records/*.json (lists of records in the same schema,
written by other tools, e.g. the solver's physics tests). The page holds the machine, every figure (matplotlib, embedded as
base64 PNG), the regressions, and a table of every record with its change against the
baseline. Exit status 1 on an accuracy regression (a checked metric that passed in the
baseline and fails now, or fails by more than it did); failed checks without a baseline and
speed changes are shown but do not change the exit status (the tests themselves fail then).
"""
from __future__ import annotations

import argparse
import base64
import datetime as _dt
import html
import io
import json
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
from harness import machine  # noqa: E402

SAME_REL = 1e-9      # value changes below this (relative) count as unchanged
SPEED_NOTE = 0.20    # timing changes beyond +-20 % are highlighted (never failed: timings are noisy)


def key(r):
    return (r["case"], r["metric"], r.get("backend") or "")


def deviation(r):
    """How far a checked record is from passing-boundary terms: |value - reference| for
    rel/abs, the value for max/min, distance outside the range for range; None if n/a."""
    v, ref, tol = r.get("value"), r.get("reference"), r.get("tolerance")
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return math.inf
    kind = r.get("kind")
    if kind in ("rel", "abs") and ref is not None:
        return abs(v - ref)
    if kind == "max":
        return v
    if kind == "min":
        return -v
    if kind == "range" and tol:
        return max(tol[0] - v, v - tol[1], 0.0)
    return None


def allowed(r):
    """The tolerance of a checked record in the units of deviation()."""
    kind, ref, tol = r.get("kind"), r.get("reference"), r.get("tolerance")
    if kind == "rel":
        return tol * abs(ref)
    if kind in ("abs", "max"):
        return tol
    if kind == "min":
        return -tol
    if kind == "range":
        return 0.0
    return None


def compare(records, baseline):
    base = {key(r): r for r in baseline.get("records", [])}
    rows, regressions = [], []
    for r in records:
        b = base.get(key(r))
        status, detail = "new", ""
        is_time = r.get("unit") == "s"
        if b is not None:
            v, bv = r.get("value"), b.get("value")
            if v is None or bv is None:
                status = "same" if v == bv else "changed"
            else:
                rel = abs(v - bv) / max(abs(bv), 1e-300)
                status = "same" if rel <= SAME_REL or v == bv else "changed"
                if status == "changed":
                    detail = f"{bv:.6g} -> {v:.6g}"
                    if is_time and bv > 0:
                        ratio = v / bv
                        detail = f"{bv:.3g} s -> {v:.3g} s (x{ratio:.2f})"
                        status = "slower" if ratio > 1 + SPEED_NOTE else "faster" if ratio < 1 - SPEED_NOTE else "same-ish"
            if r.get("kind") not in (None, "info") and not is_time:
                d, db, tol = deviation(r), deviation(b), allowed(r)
                if b.get("pass") and r.get("pass") is False:
                    status, detail = "REGRESSION", f"passed in baseline, fails now ({detail or 'value ' + str(r.get('value'))})"
                elif r.get("pass") is False and b.get("pass") is False and d is not None and db is not None \
                        and tol is not None and d - db > abs(tol):
                    status, detail = "REGRESSION", f"failed before, now worse by more than the tolerance ({detail})"
                elif status == "changed" and d is not None and db is not None:
                    status = "improved" if d < db else "worse (within tolerance)"
        if status == "REGRESSION":
            regressions.append((r, detail))
        rows.append((r, b, status, detail))
    now = {key(r) for r in records}
    missing = [b for k, b in base.items() if k not in now]
    return rows, regressions, missing


def figures(series, machine_line):
    """{figure id: base64 PNG} from the plot series."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = {}
    groups = {}
    for s in series:
        groups.setdefault(s["figure"], []).append(s)
    for fig_id, items in groups.items():
        fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=110)
        meta = {}
        for s in items:
            for k in ("title", "xlabel", "ylabel", "xscale", "yscale"):
                if s.get(k) and k not in meta:
                    meta[k] = s[k]
        for s in items:
            style = s.get("style", "line")
            if style == "hline":
                ax.axhline(s["y"][0], ls="--", lw=1, label=f"{s['label']} ({s['y'][0]:.4g})",
                           color={"Timoshenko": "tab:red", "Euler-Bernoulli": "black"}.get(s["label"], "tab:gray"))
                continue
            x, y = s["x"], s["y"]
            if meta.get("yscale") == "log":
                x, y = zip(*[(a, b) for a, b in zip(x, y) if b > 0]) if any(b > 0 for b in y) else ([], [])
            kw = dict(marker="o", ms=5) if style == "points" else dict(marker=".", ms=7, lw=1.6)
            if style == "points":
                kw["ls"] = "none"
            ax.plot(x, y, label=s["label"], **kw)
            for xi, yi, lab in zip(x, y, s.get("labels", [])):
                ax.annotate(lab, (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7, color="0.35")
        if meta.get("xscale"):
            ax.set_xscale(meta["xscale"])
        if meta.get("yscale"):
            ax.set_yscale(meta["yscale"])
        ax.set_title(meta.get("title", fig_id), fontsize=11)
        ax.set_xlabel(meta.get("xlabel", ""))
        ax.set_ylabel(meta.get("ylabel", ""))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.text(0.01, 0.005, machine_line, fontsize=6.5, color="0.4")
        fig.tight_layout(rect=(0, 0.03, 1, 1))
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
        plt.close(fig)
        out[fig_id] = base64.b64encode(buf.getvalue()).decode("ascii")
    return out


def fmt(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return "[" + ", ".join(fmt(x) for x in v) + "]"
    return html.escape(str(v))


CSS = """body{font-family:sans-serif;margin:1.5em;color:#222} table{border-collapse:collapse;font-size:12px}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:left} th{background:#eee}
.pass{color:#070}.fail{color:#b00;font-weight:bold}.REGRESSION{background:#fbb;font-weight:bold}
.changed,.worse{background:#ffd}.improved{background:#dfd}.slower{background:#fdb}.faster{background:#cfc}
.new{background:#def}.missing{color:#888}.box{border:1px solid #ccc;padding:.5em 1em;margin:.5em 0;display:inline-block}
img{width:calc(50% - 24px);min-width:480px;border:1px solid #ddd;margin:4px}"""


def build_html(records, session, baseline, rows, regressions, missing, figs, extra=""):
    m = session.get("machine") or machine.describe()
    npass = sum(r.get("pass") is True for r in records)
    nfail = sum(r.get("pass") is False for r in records)
    h = [f"<!doctype html><html><head><meta charset='utf-8'><title>qdemsph verification</title>"
         f"<style>{CSS}</style></head><body>",
         "<h1>qdemsph verification report</h1>",
         f"<div class='box'><b>Machine:</b> {html.escape(str(m.get('cpu')))}, {m.get('cores')} cores "
         f"({m.get('affinity_cores')} usable), host {html.escape(str(m.get('host')))}, {html.escape(str(m.get('os')))}<br>"
         f"<b>Run:</b> tier <b>{session.get('tier')}</b>, started {session.get('started')}, finished "
         f"{session.get('finished')}, pytest exit status {session.get('pytest_exitstatus')}, qdemsph "
         f"{html.escape(str(session.get('qdemsph')))}, backend option {session.get('backend_option')}<br>"
         f"<b>Checks:</b> <span class='pass'>{npass} pass</span>, <span class='fail'>{nfail} fail</span>, "
         f"{len(records) - npass - nfail} recorded only<br>"
         f"<b>Baseline:</b> {html.escape(str(baseline.get('accepted', 'none')))} "
         f"({html.escape(str((baseline.get('machine') or {}).get('cpu', '')))}, tier {baseline.get('tier', '-')}): "
         f"<span class='{'fail' if regressions else 'pass'}'>{len(regressions)} accuracy regression(s)</span>, "
         f"{sum(s not in ('same', 'same-ish', 'new') for _, _, s, _ in rows)} change(s), "
         f"{sum(s == 'new' for _, _, s, _ in rows)} new, {len(missing)} not run</div>"]
    if regressions:
        h.append("<h2>Accuracy regressions</h2><ul>")
        for r, d in regressions:
            h.append(f"<li class='REGRESSION'>{html.escape(r['case'])} / {html.escape(r['metric'])}: {html.escape(d)}</li>")
        h.append("</ul>")
    if figs:
        h.append("<h2>Figures</h2>")
        for fig_id, png in figs.items():
            h.append(f"<img alt='{html.escape(fig_id)}' src='data:image/png;base64,{png}'>")
    h.append(extra)
    h.append("<h2>All records</h2><table><tr><th>case</th><th>metric</th><th>value</th><th>unit</th>"
             "<th>reference</th><th>tolerance</th><th>check</th><th>pass</th><th>wall s</th><th>backend</th>"
             "<th>baseline</th><th>change</th></tr>")
    for r, b, status, detail in rows:
        ok = r.get("pass")
        cls = "pass" if ok else "fail" if ok is False else ""
        scls = status.split(" ")[0].split("-")[0]
        h.append(f"<tr><td>{fmt(r['case'])}</td><td>{fmt(r['metric'])}</td><td>{fmt(r.get('value'))}</td>"
                 f"<td>{fmt(r.get('unit'))}</td><td>{fmt(r.get('reference'))}</td><td>{fmt(r.get('tolerance'))}</td>"
                 f"<td>{fmt(r.get('kind'))}</td><td class='{cls}'>{'' if ok is None else 'pass' if ok else 'FAIL'}</td>"
                 f"<td>{fmt(r.get('wall_s'))}</td><td>{fmt(r.get('backend'))}</td>"
                 f"<td>{fmt(b.get('value')) if b else ''}</td><td class='{scls}'>{html.escape(status)}"
                 f"{': ' + html.escape(detail) if detail else ''}</td></tr>")
    for b in missing:
        h.append(f"<tr class='missing'><td>{fmt(b['case'])}</td><td>{fmt(b['metric'])}</td><td></td><td>{fmt(b.get('unit'))}</td>"
                 f"<td></td><td></td><td></td><td></td><td></td><td>{fmt(b.get('backend'))}</td><td>{fmt(b.get('value'))}</td>"
                 f"<td>not run (baseline tier {fmt(b.get('tier'))})</td></tr>")
    h.append("</table>")
    notes = [r for r in records if r.get("note")]
    if notes:
        h.append("<h2>Notes</h2><ul>")
        h += [f"<li>{fmt(r['case'])} / {fmt(r['metric'])}: {fmt(r['note'])}</li>" for r in notes]
        h.append("</ul>")
    h.append(f"<p style='color:#888'>generated {_dt.datetime.now(_dt.timezone.utc).isoformat(timespec='seconds')} "
             "by verification/report.py</p></body></html>")
    return "\n".join(h)


def accept(records, session, baseline_path):
    failing = [r for r in records if r.get("pass") is False]
    if failing:
        sys.exit(f"refusing to accept a run with {len(failing)} failing check(s) as the baseline")
    old = json.loads(baseline_path.read_text()) if baseline_path.exists() else {}
    merged = {key(r): r for r in old.get("records", [])}
    merged.update({key(r): r for r in records})  # keeps long-tier records when accepting a quick run
    doc = {"accepted": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
           "machine": session.get("machine"), "tier": session.get("tier"),
           "note": "Last accepted verification metrics; regenerate with "
                   "`/usr/bin/python3 verification/report.py --accept` after a verified run.",
           "records": sorted(merged.values(), key=lambda r: (r["case"], r["metric"], r.get("backend") or ""))}
    baseline_path.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"baseline written: {baseline_path} ({len(doc['records'])} records)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(REPO / "build" / "verify"))
    ap.add_argument("--baseline", default=str(REPO / "references" / "baseline.json"))
    ap.add_argument("--accept", action="store_true", help="write this run's records into the baseline")
    args = ap.parse_args(argv)
    out, bpath = Path(args.out), Path(args.baseline)
    spath = out / "summary.json"
    if not spath.exists():
        sys.exit(f"{spath} not found: run the verification first (make verify)")
    records = json.loads(spath.read_text())
    # Records from outside pytest (e.g. the solver's own physics tests) in the same schema.
    for extra in sorted((out / "records").glob("*.json")):
        try:
            more = json.loads(extra.read_text())
        except json.JSONDecodeError as e:
            sys.exit(f"{extra}: not JSON ({e})")
        if not isinstance(more, list) or not all(isinstance(r, dict) and "case" in r and "metric" in r for r in more):
            sys.exit(f"{extra}: expected a list of records with at least 'case' and 'metric'")
        for r in more:
            r.setdefault("source", extra.name)
        records += more
    sess_path = out / "session.json"
    session = json.loads(sess_path.read_text()) if sess_path.exists() else {}
    if args.accept:
        accept(records, session, bpath)
        return 0
    baseline = json.loads(bpath.read_text()) if bpath.exists() else {}
    rows, regressions, missing = compare(records, baseline)
    m = session.get("machine") or machine.describe()
    mline = f"{m.get('cpu')}, {m.get('cores')} cores; {session.get('tier', '?')} tier, {session.get('finished', '')}"
    figs = figures(session.get("series", []), mline)
    # Scaling records (references/benchmarks/scaling, <out>/scaling): tables and figures.
    import importlib.util

    spec = importlib.util.spec_from_file_location("scaling_report", REPO / "scaling" / "report.py")
    scaling_report = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(scaling_report)
    sfigs, shtml = scaling_report.section([out / "scaling"])
    shtml += "".join(f"<img alt='{k}' src='data:image/png;base64,{v}'>" for k, v in sfigs.items())
    (out / "report.html").write_text(build_html(records, session, baseline, rows, regressions, missing, figs, shtml))
    nfail = sum(r.get("pass") is False for r in records)
    print(f"report: {out / 'report.html'}: {len(records)} records, {nfail} failing check(s), "
          f"{len(regressions)} accuracy regression(s) against {bpath.name if baseline else 'no baseline'}")
    for r, d in regressions:
        print(f"  REGRESSION {r['case']} / {r['metric']}: {d}")
    return 1 if regressions else 0


if __name__ == "__main__":
    sys.exit(main())
