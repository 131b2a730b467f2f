"""Device time per step from an Nsight Compute kernel list: where a GPU step goes.

ncu runs the kernels one at a time, so their durations add up to the device's busy time; the
step time of the same run (its record's `step_s`) minus that is the time the device sat idle,
waiting for the host (read-backs, messages, launches). Profile one rank of a scaling run by
wrapping the binary (`scaling/run.py ... --qdemsph WRAPPER`), e.g. rank 0:

    #!/bin/bash
    if [ "$1" = run ] && [ "${OMPI_COMM_WORLD_RANK:-0}" = 0 ]; then
      exec ncu --csv --log-file ncu.csv --metrics gpu__time_duration.sum --cache-control none \\
        --clock-control none --launch-skip 3000 --launch-count 500 /path/to/qdemsph "$@"
    fi
    exec /path/to/qdemsph "$@"

then `ncu_steps.py ncu.csv [more.csv ...] [--step-ms T ...]`. The window is cut to whole
steps: from the first launch of the once-a-step kernel (`--marker`, the tets' corner gather
by default) to the last. Kernels are grouped by the function their lambda is written in
(`for_each` and reductions) or by their CUB kernel's name; `*.csv.gz` is read too.
"""
import argparse
import csv
import gzip
import re
import sys
from collections import defaultdict
from pathlib import Path

LAMBDA = re.compile(r"(\w+)\([^()]*\)::\[lambda\(long\) \(instance (\d+)\)\]")
LAUNCHER = re.compile(r"(\w+_kernel)\b")
CUB = re.compile(r"::(Device\w+Kernel)\b")


def group(name: str) -> str:
    """A kernel's group: `function#instance` of its lambda, `launcher:function` for a generic
    launcher whose lambda has no instance number, or the CUB kernel's name."""
    m = CUB.search(name)
    if m:
        return "cub:" + m.group(1)
    m = LAMBDA.search(name)
    if m:
        return f"{m.group(1)}#{m.group(2)}"
    fn = re.search(r"(\w+)\([^()]*\)::\[lambda", name)
    launcher = LAUNCHER.search(name)
    if fn:
        return f"{launcher.group(1) if launcher else 'kernel'}:{fn.group(1)}"
    return launcher.group(1) if launcher else name[:60]


def read(path: str) -> list[tuple[str, float]]:
    """(group, microseconds) per kernel launch, in launch order."""
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        lines = [line for line in f if line.startswith('"')]  # ncu's own messages come first
    out = []
    for r in csv.DictReader(lines):
        if r.get("Metric Name") != "gpu__time_duration.sum":
            continue
        scale = {"ns": 1e-3, "us": 1.0, "usecond": 1.0, "ms": 1e3, "msecond": 1e3}[r["Metric Unit"]]
        out.append((group(r["Kernel Name"]), float(r["Metric Value"].replace(",", "")) * scale))
    return out


def per_step(kernels: list[tuple[str, float]], marker: str) -> tuple[int, dict, dict]:
    """(whole steps, {group: us a step}, {group: launches a step}) over the window from the
    first launch of `marker` to its last."""
    at = [i for i, (g, _) in enumerate(kernels) if marker in g]
    if len(at) < 2:
        raise ValueError(f"fewer than two launches of the marker kernel '{marker}' in the window")
    steps = len(at) - 1
    us, calls = defaultdict(float), defaultdict(float)
    for g, t in kernels[at[0]:at[-1]]:
        us[g] += t / steps
        calls[g] += 1 / steps
    return steps, dict(us), dict(calls)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv", nargs="+", help="ncu --csv logs (gpu__time_duration.sum), .gz too")
    ap.add_argument("--marker", default="assemble_forces", help="a kernel launched once a step")
    ap.add_argument("--step-ms", type=float, nargs="*", default=[], help="each run's step time: prints idle")
    a = ap.parse_args(argv)
    runs = [per_step(read(p), a.marker) for p in a.csv]
    groups = sorted({g for _, us, _ in runs for g in us}, key=lambda g: -max(r[1].get(g, 0.0) for r in runs))
    print("| kernels | " + " | ".join(f"{Path(p).name} (us a step, launches)" for p in a.csv) + " |")
    print("|---|" + "---:|" * len(runs))
    for g in groups:
        print(f"| {g} | " + " | ".join(f"{us.get(g, 0.0):.1f} ({calls.get(g, 0.0):.2f})" for _, us, calls in runs) + " |")
    busy = [sum(us.values()) for _, us, _ in runs]
    print("| **busy** | " + " | ".join(f"**{b:.1f}**" for b in busy) + " |")
    if a.step_ms:
        if len(a.step_ms) != len(runs):
            ap.error("--step-ms: one step time per CSV")
        print("| step | " + " | ".join(f"{t * 1e3:.1f}" for t in a.step_ms) + " |")
        print("| **idle** | " + " | ".join(f"**{t * 1e3 - b:.1f}**" for t, b in zip(a.step_ms, busy)) + " |")
    print("\nwhole steps in the windows: " + ", ".join(str(s) for s, _, _ in runs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
