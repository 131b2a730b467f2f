"""pytest harness for qdemsph verification (run with Debian's /usr/bin/python3).

Options: --full (long tier), --backend NAME (passed to `qdemsph run --backend NAME`),
--qdemsph PATH (default $QDEMSPH or build/bin/qdemsph), --verify-out DIR (default build/verify),
--threads N (qdemsph CPU threads, default 1), --run-timeout SECONDS (per solver process,
default 3600).

Every test records its metrics through the `checks` fixture:
    checks.check(metric, value, kind=..., reference=..., tolerance=..., unit=..., wall_s=...)
    checks.series(figure, label, x, y, ...)   # data the report plots
    checks.require()                          # fails the test listing every failed metric
At the end of the session the records go to <out>/summary.json (a list of
{case, metric, value, reference, tolerance, unit, pass, wall_s, backend, kind, test, tier})
and the plot data, machine and run description to <out>/session.json; report.py reads both.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from harness import machine  # noqa: E402
from harness.paths import DEFAULT_OUT, DEFAULT_QDEMSPH, REPO  # noqa: E402
from harness.qdemsph import Qdemsph  # noqa: E402

KINDS = {
    "max": "value <= tolerance",
    "min": "value >= tolerance",
    "rel": "|value - reference| <= tolerance * |reference|",
    "abs": "|value - reference| <= tolerance",
    "range": "tolerance[0] <= value <= tolerance[1]",
    "info": "recorded, not checked",
}


def pytest_addoption(parser):
    g = parser.getgroup("qdemsph verification")
    g.addoption("--full", action="store_true", help="run the long tier (large meshes)")
    g.addoption("--backend", default=None, help="qdemsph backend (sets run.backend); default: the solver's")
    g.addoption("--qdemsph", default=None, help="path to the qdemsph binary (default $QDEMSPH or build/bin/qdemsph)")
    g.addoption("--verify-out", default=None, help="output folder (default build/verify)")
    g.addoption("--threads", type=int, default=1,
                help="CPU threads per qdemsph run (run.threads; default 1, like the single-threaded "
                     "FEniCSx references; 0 = the solver's default)")
    g.addoption("--run-timeout", type=float, default=3600.0,
                help="seconds one qdemsph or FEniCSx process may run before it counts as failed")


def pytest_configure(config):
    out = Path(config.getoption("--verify-out") or DEFAULT_OUT)
    if not out.is_absolute():
        out = REPO / out
    config._qv = {
        "out": out, "records": [], "series": [],
        "tier": "full" if config.getoption("--full") else "quick",
        "started": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }


def pytest_collection_modifyitems(config, items):
    if config.getoption("--full"):
        return
    skip = pytest.mark.skip(reason="long tier: run with --full (make verify FULL=1)")
    for item in items:
        if "full" in item.keywords:
            item.add_marker(skip)


def _case_of(path):
    path = Path(path)
    parts = path.parts
    return parts[parts.index("cases") + 1] if "cases" in parts else path.stem


class Checks:
    def __init__(self, state, case, test, backend):
        self._state, self.case, self.test, self.backend = state, case, test, backend
        self.failed = []
        self.required = False

    def check(self, metric, value, *, kind, reference=None, tolerance=None, unit="",
              wall_s=None, backend=None, note=""):
        if kind not in KINDS:
            raise ValueError(f"unknown check kind {kind!r}; one of {sorted(KINDS)}")
        value = None if value is None else float(value)
        ok = None
        if kind != "info":
            bad = value is None or not math.isfinite(value)
            if kind == "max":
                ok = not bad and value <= tolerance
            elif kind == "min":
                ok = not bad and value >= tolerance
            elif kind == "rel":
                ok = not bad and abs(value - reference) <= tolerance * abs(reference)
            elif kind == "abs":
                ok = not bad and abs(value - reference) <= tolerance
            elif kind == "range":
                ok = not bad and tolerance[0] <= value <= tolerance[1]
            ok = bool(ok)
        rec = {"case": self.case, "metric": metric, "value": value, "reference": reference,
               "tolerance": tolerance, "unit": unit, "pass": ok,
               "wall_s": None if wall_s is None else float(wall_s),
               "backend": backend or self.backend, "kind": kind, "test": self.test,
               "tier": self._state["tier"]}
        if note:
            rec["note"] = note
        self._state["records"].append(rec)
        if ok is False:
            self.failed.append(f"{metric} = {value:.6g} {unit} fails {kind} check "
                               f"(reference {reference}, tolerance {tolerance}: {KINDS[kind]})"
                               if value is not None else f"{metric}: no value")
        return ok

    def info(self, metric, value, unit="", **kw):
        return self.check(metric, value, kind="info", unit=unit, **kw)

    def series(self, figure, label, x, y, **meta):
        """One line of a figure in the report. meta: xlabel, ylabel, title, xscale, yscale,
        style ('line', 'points', 'hline'), note."""
        self._state["series"].append({"case": self.case, "figure": figure, "label": label,
                                      "x": [float(v) for v in x], "y": [float(v) for v in y], **meta})

    def require(self):
        self.required = True
        if self.failed:
            pytest.fail(f"{len(self.failed)} metric(s) out of tolerance in {self.case}:\n  "
                        + "\n  ".join(self.failed), pytrace=False)


@pytest.fixture
def checks(request):
    state = request.config._qv
    c = Checks(state, _case_of(request.node.path), request.node.nodeid,
               request.config.getoption("--backend") or "")
    yield c
    if c.failed and not c.required:
        pytest.fail("metrics failed but the test did not call checks.require():\n  " + "\n  ".join(c.failed))


@pytest.fixture(scope="session")
def tier(request):
    return request.config._qv["tier"]


@pytest.fixture(scope="session")
def qdemsph(request):
    binary = request.config.getoption("--qdemsph") or os.environ.get("QDEMSPH") or DEFAULT_QDEMSPH
    binary = Path(binary)
    if not binary.is_absolute():
        binary = REPO / binary
    return Qdemsph(binary, backend=request.config.getoption("--backend"),
                   timeout_s=request.config.getoption("--run-timeout"),
                   threads=request.config.getoption("--threads"))


@pytest.fixture
def case_out(request):
    """A clean output folder build/verify/cases/<case>/<test name>."""
    import shutil

    d = request.config._qv["out"] / "cases" / _case_of(request.node.path) / request.node.name
    d = Path(str(d).replace("[", "_").replace("]", ""))
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    return d


def pytest_sessionfinish(session, exitstatus):
    state = getattr(session.config, "_qv", None)
    if state is None or getattr(session.config, "workerinput", None) is not None:
        return
    out = state["out"]
    out.mkdir(parents=True, exist_ok=True)
    (out / "summary.json").write_text(json.dumps(state["records"], indent=1) + "\n")
    meta = {
        "started": state["started"],
        "finished": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "tier": state["tier"], "pytest_exitstatus": int(exitstatus),
        "backend_option": session.config.getoption("--backend"),
        "threads_option": session.config.getoption("--threads"),
        "qdemsph": str(session.config.getoption("--qdemsph") or os.environ.get("QDEMSPH") or DEFAULT_QDEMSPH),
        "machine": machine.describe(), "series": state["series"],
    }
    (out / "session.json").write_text(json.dumps(meta, indent=1) + "\n")
