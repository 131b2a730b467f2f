#!/usr/bin/env python3
"""Table of an Nsight Compute log (ncu --metrics ... --log-file F): per kernel launch, the
enclosing function of its lambda (the stage), time, DRAM bytes, registers, active warps and L1
hit rate; then the time per stage summed over the launches.

  python3 ci/gpu/ncu_table.py ncu.txt"""
import re
import sys
from collections import defaultdict

UNIT = {"byte": 1, "Kbyte": 1e3, "Mbyte": 1e6, "Gbyte": 1e9, "ns": 1e-9, "us": 1e-6, "usecond": 1e-6,
        "ms": 1e-3, "msecond": 1e-3, "nsecond": 1e-9, "%": 1, "register/thread": 1}


def stage(name):
    m = re.search(r"([A-Za-z_]\w*(?:<[^()]*>)?::\w+)\([^()]*\)::\[lambda", name)
    if m:
        return re.sub(r"^\w+_kernel<", "", re.sub(r"<[^<>]*>", "", m.group(1)))
    return re.sub(r"\(.*", "", name)[:60]


def main(path):
    launches, cur = [], None
    for line in open(path, errors="replace"):
        if re.match(r"^\s{2}\S.*\(\d+, \d+, \d+\)x\(\d+, \d+, \d+\)", line):
            cur = {"name": stage(line.strip())}
            launches.append(cur)
            continue
        m = re.match(r"^\s+(\S+)\s+(\S+)\s+([\d.,]+)\s*$", line)
        if cur is not None and m:
            cur[m.group(1)] = float(m.group(3).replace(",", "")) * UNIT.get(m.group(2), 1)
    if not launches:
        print("NCU no kernels found in", path)
        return
    total = defaultdict(float)
    print(f"{'kernel (enclosing function)':52s} {'us':>9s} {'DRAM MB':>9s} {'regs':>5s} {'warps%':>7s} {'L1 hit%':>8s}")
    for k in launches:
        t = k.get("gpu__time_duration.sum", 0)
        total[k["name"]] += t
        mb = (k.get("dram__bytes_read.sum", 0) + k.get("dram__bytes_write.sum", 0)) / 1e6
        print(f"{k['name'][:52]:52s} {t * 1e6:9.1f} {mb:9.1f} {k.get('launch__registers_per_thread', 0):5.0f} "
              f"{k.get('sm__warps_active.avg.pct_of_peak_sustained_active', 0):7.1f} "
              f"{k.get('l1tex__t_sector_hit_rate.pct', 0):8.1f}")
    print("NCU per stage (us, summed over the launches above):")
    for n, t in sorted(total.items(), key=lambda kv: -kv[1]):
        print(f"NCU {n[:60]:60s} {t * 1e6:9.1f}")


if __name__ == "__main__":
    main(sys.argv[1])
