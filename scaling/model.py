#!/usr/bin/python3
"""Performance model of the distributed stepper: time per step on N ranks, weak-scaling
efficiency from 1 to 512 ranks (GPUs or CPU cores). Its outputs are PREDICTIONS; the
measured records (run.py) calibrate it and are compared with it (report.py).

Time per step of rank r (the step ends when the slowest rank ends):

  T(N) = max_r [ C_r + X_r ] * (1 + s sqrt(2 ln N)) + A(N) + B

  C_r  compute: c_tet * held_tets_r + c_vertex * owned_vertices_r + c_pair * pairs_r
       + c_particle * (owned_particles_r + g * ghost_particles_r) + c_step
       held tets = home tets + halo tets (a tet is computed on every rank owning one of its
       vertices, docs/parallel.md item 1: redundant work at the cuts); pairs_r = pairs per
       surface vertex x (owned + k ghost surface vertices): a rank finds candidate pairs
       among all the surface it holds, ghosts included. k = 0.25 measured (below); before
       whole bodies led their body pairs it was 0.6 (`geometry.py
       --validate`, pairs(N) / (N pairs(1)) = 1 + k ghost surface / owned surface): cube
       block on 2 H100s at d32fc91, pairs 1.074 x the 1-rank pairs while the held surface was
       1.125 x the owned, k = 0.59 (references/benchmarks/scaling/2026-11-26_x2_skin_overlap/
       call5_h100/; in time too: the slower rank's contact and element kernels 1.708 ->
       1.838 ms/step, k = 0.58-0.61 at h100-d32fc91's pair cost); on 2, 4, 8, 16, 32 CPU
       ranks (5d4f73b, 27 cubes a rank, 2026-11-26_h200x2/call5_cpu/) k = 0.77, 0.70, 0.26,
       0.48, 0.29. It was 1.4 when every rank evaluated every pair it held (wip-mpi aef1376,
       CPU ranks 2, 4, 8: pairs 1.34, 1.80, 3.00 x with the held surface 1.25, 1.56, 2.44 x:
       k = 1.38, 1.43, 1.38; references/benchmarks/scaling/halo_validation_cubes_devvm.json).
       Since whole bodies lead their body pairs (5038aab: one rank searches a pair with a whole
       body) the cube block gives k = 0.27 / 0.21 on 2 / 4 H200s (pairs 1.034 / 1.067 x;
       references/benchmarks/scaling/2026-11-26_h200_whole_bodies_lead/; the same at 05319f8,
       2026-11-27_x4_pool_merge/call4_h200x4/): the default, 0.25, which the cost set
       h200-05319f8 and the fitted round trip go with.
       k = 0: every candidate pair of border primitives searched on one rank only;
       g: the share of a particle's work a ghost costs, 0.15 (a ghost is sorted into the cell
       list; the density and force loops run over owned particles only).
       Balancer: when max_r C_r / mean C - 1 exceeds the rebalance threshold (0.10, the
       stepper's default), the pieces are re-cut on measured time and the compute becomes
       mean C x (1 + the cut's own imbalance); below it (or with a static partition,
       threshold None) the slowest rank's C_r stands.
  X_r  halo exchange, not hidden (overlap o in [0, 1] hides up to o C_r behind interior work):
       max(0, E [k_r a_intra + k'_r a_inter + b_intra_r / B_intra + b_inter_r / B_inter
              + stage] + R t_rt - o C_r)
       E exchanges per step (state gather, contact-force scatter-add / SPH density),
       k_r, k'_r neighbour ranks on / off the node, b bytes received per exchange
       (ghost vertices x vertex_bytes + ghost particles x particle_bytes, split on / off
       node), stage = 2 (a_stage + b_r / B_stage) when halo data crosses PCIe to be packed
       on the host (today's CommEngine packs host arrays); R host round trips per step of a
       GPU rank (each: a device synchronisation, pack / unpack launches, host MPI progress;
       bodies R = 3: the x, v halo, the contact shares, the skin test's allreduce, the first
       and the last beside the interior tets' kernels; fluid R = 4: the skin test, the x, v
       refresh and two rho, p, m refreshes), t_rt per round trip (Network.round_trip: 0 on
       CPU ranks; IPC_ROUND_TRIP).
  s    per-rank jitter (relative standard deviation of a rank's step time): the expected
       maximum of N ranks grows as s sqrt(2 ln N) (Gaussian extreme value).
  A(N) allreduce(s) per step (dt, energies): n_ar ceil(log2 N) a (on a node the host MPI
       latency, Network.host_latency where halos are device copies; a_inter beyond one node).
  B    rebalancing and plan rebuilds amortised: (migrated bytes / B + N a) / interval.

Inputs: the partition geometry (geometry.py: per-rank held tets, owned items, ghosts,
neighbours, on / off node), per-item costs (calibrated from single-rank records, see
`calibrate`), a network (NETWORKS, defaults documented there) and options.

  /usr/bin/python3 scaling/model.py predict --geometry G.json --costs h200 --network staged-ndr
  /usr/bin/python3 scaling/model.py calibrate RECORDS.json ...   # per-item costs from records
  /usr/bin/python3 scaling/model.py fit-round-trip --costs NAME RECORDS_n2.json ...  # t_rt
"""
from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
from dataclasses import asdict, dataclass, replace
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent


@dataclass
class Costs:
    """Seconds per item per step on one rank (one CPU core or one GPU)."""
    tet: float
    vertex: float
    pair: float
    particle: float
    step: float = 0.0  # fixed per step (kernel launches, checks)
    label: str = ""
    source: str = ""


@dataclass
class Network:
    """Latency a [s] per message and bandwidth B [B/s] per rank and direction."""
    name: str
    intra_latency: float
    intra_bandwidth: float
    inter_latency: float
    inter_bandwidth: float
    ranks_per_node: int
    stage_latency: float = 0.0  # per exchange and direction; 0 with stage_bandwidth 0: no staging
    stage_bandwidth: float = 0.0
    note: str = ""
    round_trip: float = 0.0  # per host round trip of a GPU rank (Options.round_trips)
    stage_offnode_only: bool = False  # on a node halos stay in device memory (CUDA IPC)
    # Host MPI latency per message on a node, for the collectives (allreduce, rebalancing):
    # where halos move by device copies, intra_latency is the copy's, not the host's. None: the same.
    host_latency: float | None = None


# Defaults, stated (vendor figures, derated to what MPI typically achieves):
#  * NVLink 4 (H100/H200 SXM): 900 GB/s bidirectional per GPU; CUDA-aware MPI peer copies reach
#    ~150 GB/s per direction for MB messages, ~3 us latency.
#  * InfiniBand NDR 400 Gb/s = 50 GB/s per port (HDR: 25 GB/s); MPI achieves ~90 % of it,
#    latency ~2 us host-to-host (GPUDirect RDMA ~3 us), one NIC per GPU (DGX H100 layout).
#  * PCIe Gen5 x16 (H100/H200 SXM host link): 64 GB/s theoretical, ~25 GB/s for the mid-size
#    pinned/pageable copies of packed halos, ~10 us per copy + pack/unpack kernel launch.
#  * Host shared memory (Open MPI vader, CMA single copy): ~0.5 us, ~5-10 GB/s per pair
#    (4.7 GB/s measured for 16 MB messages on the 2-core dev VM, `scaling/pingpong.c`).
#  * Host round trip of a GPU rank: 150 us, calibrated on the two-H100 host (2026-11-25, pinned
#    staging, references/benchmarks/scaling/2026-11-25_h100x2/): topple-weak on 2 GPUs took
#    1.70 ms/step against 1.25 predicted without it, (1.70 - 1.25) / 3 round trips; with it the
#    model gives cubes-weak 5.82 (measured 5.99) and dambreak-weak 6.70 (measured 7.06) ms/step.
# Host round trip of a GPU rank with device-resident halos (ipc-ndr): least squares over the
# three weak cases on 2 and 4 H200s at 05319f8, their in-run rebuilds taken out (`model.py
# fit-round-trip --costs h200-05319f8`, k 0.25; references/benchmarks/scaling/
# 2026-11-27_x4_pool_merge/call4_h200x4/N_*/records/*_n2.json, *_n4.json, medians): measured
# minus predicted without it, cube block +0.068 / +0.057 ms at 2 / 4 GPUs (3 round trips),
# dominoes +0.180 / +0.190 (3), dam break +0.320 / +0.472 (4) -> 68.4 us per round trip (65.2
# before the allreduce took the host's latency, Network.host_latency). One constant fits badly:
# residuals -0.137 / -0.148, -0.025 / -0.016, +0.046 / +0.199 ms. Per round trip the cube block
# asks 19-23 us, the dominoes 60-63 (their one-GPU step is 0.442 ms at the set's cube-block tet
# and pair costs, 0.564 measured) and the dam break 80-118. Two of the bodies' three round trips
# (the x, v halo and the skin test's allreduce) run while the device computes the interior tets,
# and the contact shares' behind the element gather; the fluid's four each follow a device
# synchronisation (skin test; the x, v and two rho, p, m refreshes). The counts stand (the host
# still waits and runs MPI that often); the overlap shows as the bodies' lower time per round
# trip, which one constant averages. Since then the cube block's round trips hide entirely: at
# e16c73f (4 x H100) and 1becfa5 (4 x H200) the fit over its own 2- and 4-GPU records gives
# -10 and -6 us (scaling/README.md). Before: 62.5 us at d32fc91 (costs h100-d32fc91, k 0.6, two
# H100s, 2026-11-26_x2_skin_overlap/: cubes +0.063 ms, dominoes +0.213, dam break +0.324), 67 us
# at 01b2aab (costs h100-ipc, k 1.4).
IPC_ROUND_TRIP = 68.4e-6

#  * CUDA IPC peer copies between the two H100s of one host (NVLink, scaling/probes/devicecomm.cu,
#    2026-11-25): 8 B 7.6 us (copy + stream synchronisation), 1 MB 10.7 us (98 GB/s), 16 MB 53 us
#    (316 GB/s); the hand-shake messages add ~1 us. The host round trip of a GPU rank with these
#    halos: IPC_ROUND_TRIP above.
NETWORKS = {
    # What the code does today on GPUs: on a node, halo records stay in device memory and move
    # by CUDA IPC peer copies (CommEngine::use_device); between nodes they are staged through
    # host memory (D2H, MPI, H2D): the GPU machines' Open MPI is not CUDA-aware.
    # Host MPI on a node: MPI_Allreduce of one double 1.19 us on 4 ranks, 0.54 on 2 (a 4 x H200
    # host, 2026-11-27, 2026-11-27_merge_beside_gather/README.md): 0.6 us a stage.
    "ipc-ndr": Network("ipc-ndr", 8e-6, 100e9, 2e-6, 45e9, 8, 10e-6, 25e9, round_trip=IPC_ROUND_TRIP,
                       stage_offnode_only=True, host_latency=0.6e-6,
                       note="GPU halos in device memory on a node (CUDA IPC over NVLink, measured), staged "
                       "through host memory between nodes over InfiniBand NDR; 8 GPUs per node; host round "
                       "trips calibrated on two H100s"),
    # Before 2026-11-25 (4990d7e): every GPU halo packed on the host (D2H, MPI, H2D).
    "staged-ndr": Network("staged-ndr", 0.5e-6, 8e9, 2e-6, 45e9, 8, 10e-6, 25e9, round_trip=150e-6,
                          note="GPU halos staged through host memory over PCIe Gen5; host MPI over shared "
                          "memory on a node and InfiniBand NDR between nodes; 8 GPUs per node; "
                          "150 us per host round trip (measured, two H100s)"),
    # With GPU-resident pack/unpack and CUDA-aware MPI (docs/parallel.md: not done yet).
    "cuda-aware-ndr": Network("cuda-aware-ndr", 3e-6, 150e9, 3e-6, 45e9, 8, 0.0, 0.0,
                              note="GPU-resident halos, CUDA-aware MPI: NVLink 4 on a node, GPUDirect RDMA "
                              "over InfiniBand NDR between nodes; 8 GPUs per node; no host round trips "
                              "(a bound: stream-ordered exchanges, not built)"),
    "staged-hdr": Network("staged-hdr", 0.5e-6, 8e9, 2e-6, 22e9, 4, 10e-6, 20e9, round_trip=150e-6,
                          note="host-staged halos, InfiniBand HDR 200 Gb/s, 4 GPUs per node; 150 us per host "
                          "round trip (measured, two H100s)"),
    # CPU ranks (one per core) on one node; between nodes InfiniBand NDR shared by the node's ranks.
    "cpu-shm": Network("cpu-shm", 0.5e-6, 5e9, 2e-6, 45e9 / 64, 64, 0.0, 0.0,
                       "CPU ranks: Open MPI shared memory on a node (~0.5 us, 5 GB/s per pair); "
                       "InfiniBand NDR shared by 64 ranks per node between nodes"),
    # The report's machine, for comparison: TSUBAME 2.5 (QDR InfiniBand x2 rails, 12 cores/node).
    "tsubame25": Network("tsubame25", 0.5e-6, 5e9, 2.5e-6, 8e9 / 12, 12, 0.0, 0.0,
                         "TSUBAME 2.5 CPU nodes: 2 x QDR InfiniBand (2 x 4 GB/s) shared by 12 cores"),
    "ideal": Network("ideal", 0.0, math.inf, 0.0, math.inf, 1 << 30, 0.0, 0.0, "no communication cost"),
}


@dataclass
class Options:
    vertex_bytes: float = 48.0    # x, v per ghost and force evaluation (measured: 45.5 B per
    #                               geometry-predicted ghost, 2 CPU ranks of the cube block)
    particle_bytes: float = 112.0  # SPH: x, v, rho, p, then rho, p again (assumed)
    exchanges: int = 1            # halo exchanges per step (each: one message per neighbour)
    round_trips: int = 0          # host round trips per step of a GPU rank (x Network.round_trip)
    overlap: float = 0.0          # share of the compute that can hide communication (0: none)
    jitter: float = 0.01          # s: relative std. deviation of a rank's step time
    ghost_particle_work: float = 0.15  # ghosts are binned/sorted; density and forces loop over owned
    rebalance_threshold: float | None = 0.10  # the stepper's default; None: static partition
    allreduces: int = 1
    rebalance_interval: int = 0   # steps between rebalances (0: none)
    migrated_bytes: float = 0.0   # per rebalance, per rank
    pairs_per_surface_vertex: float = 0.0
    ghost_pair_weight: float = 0.25  # k: candidate pairs per ghost surface vertex / per owned one
    rebuild_s_per_step: float = 0.0  # ghost / layout rebuilds during the run, amortised (measured:
    #                                  a host-side rebuild times rebuilds per step; the same per
    #                                  rank in weak scaling, the global displacement triggers it)


def _terms(geo: dict, r: int, costs: Costs, net: Network, opt: Options, N: int) -> dict:
    """Compute and exchange seconds of rank r of one geometry row, on N ranks in all."""
    g = lambda k: float(geo[k][r]) if k in geo and len(geo[k]) > r else 0.0  # noqa: E731
    C = (costs.tet * g("held_tets") + costs.vertex * g("owned_vertices")
         + costs.pair * opt.pairs_per_surface_vertex
         * (g("owned_surface_vertices") + opt.ghost_pair_weight * g("ghost_surface_vertices"))
         + costs.particle * (g("owned_particles") + opt.ghost_particle_work * g("ghost_particles")) + costs.step)
    if N == 1:
        return {"compute": C, "exchange": 0.0, "exchange_raw": 0.0}
    rpn = net.ranks_per_node
    gv, gp = g("ghost_vertices"), g("ghost_particles")
    # the node split of the geometry for this node size, or else for the largest smaller one
    # (more traffic off node: conservative); none: everything off node
    have = [int(k[len("ghost_vertices_offnode_rpn"):]) for k in geo
            if k.startswith("ghost_vertices_offnode_rpn") and k[len("ghost_vertices_offnode_rpn"):].isdigit()]
    use = max([q for q in have if q <= rpn], default=None)
    if N <= rpn:  # one node
        gv_off = gp_off = k_off = 0.0
    elif use is not None and N > use:
        key = f"_offnode_rpn{use}"
        gv_off, gp_off, k_off = g("ghost_vertices" + key), g("ghost_particles" + key), g("recv_neighbours" + key)
    else:
        gv_off, gp_off, k_off = gv, gp, g("recv_neighbours")
    k = g("recv_neighbours")
    b_on = (gv - gv_off) * opt.vertex_bytes + (gp - gp_off) * opt.particle_bytes
    b_off = gv_off * opt.vertex_bytes + gp_off * opt.particle_bytes
    lat = (k - k_off) * net.intra_latency + k_off * net.inter_latency
    bw = (b_on / net.intra_bandwidth if b_on else 0.0) + (b_off / net.inter_bandwidth if b_off else 0.0)
    b_stage = b_off if net.stage_offnode_only else b_on + b_off
    stage = 2 * (net.stage_latency + b_stage / net.stage_bandwidth) if net.stage_bandwidth > 0 and b_stage else 0.0
    rt = opt.round_trips * net.round_trip
    X = opt.exchanges * (lat + bw + stage) + rt
    return {"compute": C, "exchange_raw": X, "exchange": max(0.0, X - opt.overlap * C),
            "latency": opt.exchanges * lat, "bandwidth": opt.exchanges * bw, "staging": opt.exchanges * stage,
            "round_trips": rt,
            "bytes": b_on + b_off, "bytes_offnode": b_off}


def round_trips(has_fluid: bool) -> int:
    """Host round trips per step of a GPU rank (module docstring): fluid 4, bodies 3."""
    return 4 if has_fluid else 3


def geometry_round_trips(geo: dict) -> int:
    """round_trips() of a geometry record's scene (geometry.py): fluid when a row owns particles."""
    return round_trips(any(sum(g.get("owned_particles", [0])) > 0 for g in geo["rows"]))


def step_time(geo: dict, costs: Costs, net: Network, opt: Options) -> dict:
    """Predicted time per step for one geometry row (geometry.py output for N ranks). An
    extrapolated row (extend_rows) holds candidate rows of smaller N: each is evaluated as if
    on N ranks (latencies, jitter, allreduce of N) and the slowest is the prediction."""
    if geo.get("candidates"):
        outs = [step_time(dict(c, ranks=geo["ranks"], _per_rank_of=c["ranks"]), costs, net, opt)
                for c in geo["candidates"]]
        worst = max(outs, key=lambda o: o["step_s"])
        return dict(worst, geometry_from_ranks=worst.get("geometry_from_ranks"))
    N = int(geo["ranks"])
    n_rows = int(geo.get("_per_rank_of", N))  # per-rank lists of a smaller N (extrapolation)
    per = [_terms(geo, r, costs, net, opt, N) for r in range(n_rows)]
    mean_c = sum(p["compute"] for p in per) / n_rows
    crit = max(range(n_rows), key=lambda r: per[r]["compute"] + per[r]["exchange"])
    xmax = max(range(n_rows), key=lambda r: per[r]["exchange"])
    static_imb = max(p["compute"] for p in per) / mean_c - 1 if mean_c > 0 else 0.0
    if opt.rebalance_threshold is not None and static_imb > opt.rebalance_threshold:
        # The balancer re-cuts on measured time (redundant halo tets and ghost work included):
        # the compute evens out to the cut's granularity (the partition's own imbalance).
        compute = mean_c * (1 + float(geo.get("imbalance_partition", 0.0)))
        busy, xr, balanced = compute + per[xmax]["exchange"], xmax, True
    else:  # static partition, or an imbalance below the threshold (no rebalance triggered)
        compute, busy, xr, balanced = per[crit]["compute"], per[crit]["compute"] + per[crit]["exchange"], crit, False
    jit = opt.jitter * math.sqrt(2 * math.log(N)) if N > 1 else 0.0
    on_node = net.intra_latency if net.host_latency is None else net.host_latency
    lat_ar = on_node if N <= net.ranks_per_node else net.inter_latency
    ar = opt.allreduces * math.ceil(math.log2(N)) * lat_ar if N > 1 else 0.0
    reb = 0.0
    if opt.rebalance_interval > 0 and N > 1:
        bwm = net.intra_bandwidth if N <= net.ranks_per_node else net.inter_bandwidth
        reb = (opt.migrated_bytes / bwm + N * lat_ar) / opt.rebalance_interval
    rb = opt.rebuild_s_per_step if N > 1 else 0.0
    T = busy * (1 + jit) + ar + reb + rb
    x = per[xr]
    return {"ranks": N, "geometry_from_ranks": n_rows, "step_s": T, "critical_rank": xr, "compute_s": compute,
            "compute_mean_s": mean_c, "exchange_s": x["exchange"], "exchange_raw_s": x["exchange_raw"],
            "latency_s": x.get("latency", 0.0), "bandwidth_s": x.get("bandwidth", 0.0),
            "staging_s": x.get("staging", 0.0), "round_trip_s": x.get("round_trips", 0.0),
            "halo_bytes_per_exchange": x.get("bytes", 0.0),
            "jitter_s": busy * jit, "allreduce_s": ar, "rebalance_s": reb, "rebuild_s": rb, "rebalanced": balanced,
            "imbalance_static": static_imb, "imbalance": compute / mean_c - 1 if mean_c > 0 else 0.0}


def predict(rows: list[dict], costs: Costs, net: Network, opt: Options, refs=(1, 8)) -> list[dict]:
    """Step time and weak-scaling efficiency t(ref) / t(N) for every geometry row."""
    out = [dict(step_time(g, costs, net, opt), extrapolated=bool(g.get("extrapolated"))) for g in rows]
    by_n = {o["ranks"]: o["step_s"] for o in out}
    for o in out:
        for ref in refs:
            if ref in by_n and o["ranks"] >= ref:
                o[f"efficiency_vs_{ref}"] = by_n[ref] / o["step_s"]
    return out


def extend_rows(rows: list[dict], ranks: list[int], min_candidate: int = 16) -> list[dict]:
    """Geometry rows for rank counts beyond the computed ones. A weak-scaling piece keeps its
    size, but the worst piece's halo wanders with N (the cuts fall differently through the
    bodies), so an extrapolated N gets every computed row with N >= min_candidate (or the
    largest) as candidates, and step_time takes the slowest: a conservative envelope."""
    have = {g["ranks"]: g for g in rows}
    top = max(have)
    cands = [have[n] for n in sorted(have) if n >= min_candidate] or [have[top]]
    out = [have[n] for n in sorted(have)]
    for n in ranks:
        if n in have:
            continue
        if n < top:
            raise ValueError(f"no geometry row for N={n} (between computed rank counts)")
        out.append({"ranks": n, "extrapolated": True, "candidates": cands})
    return sorted(out, key=lambda g: g["ranks"])


# --- host round trip ---------------------------------------------------------------------

def fit_round_trip(cases: list[dict]) -> dict:
    """Least squares host round trip t of a GPU rank over cases {"measured_s": a step without
    its in-run rebuilds, "predicted_s": the model's step without round trips, "round_trips":
    R}: t minimises sum (d - R t)^2 with d = measured - predicted, t = sum R d / sum R^2. Each
    case gets d ("diff_s") and its residual d - R t ("residual_s"). step_time also applies the
    jitter factor to the round trips (1 + 0.01 sqrt(2 ln 2): 1.2 % more than R t on 2 ranks); the
    fit leaves it out, as the calibrations before it did."""
    t = sum(c["round_trips"] * (c["measured_s"] - c["predicted_s"]) for c in cases) / sum(
        c["round_trips"] ** 2 for c in cases)
    return {"round_trip_s": t,
            "cases": [dict(c, diff_s=c["measured_s"] - c["predicted_s"],
                           residual_s=c["measured_s"] - c["predicted_s"] - c["round_trips"] * t) for c in cases]}


def round_trip_cases(records: list[dict], costs: Costs, net: Network, ghost_pairs: float,
                     geometry_dir: Path, pairs_per_surface_vertex: dict) -> list[dict]:
    """Cases for fit_round_trip from multi-rank records of weak sweeps, one case per sweep:
    measured = the median over its records of step_s less the in-run rebuilds and rebalances
    (phases_per_step migration + balance), predicted = step_time of its geometry row
    (geometry_<sweep>_<preset>.json in geometry_dir) without round trips, R = round_trips()."""
    by = {}
    for r in records:
        by.setdefault((r["sweep"], r["preset"], r["ranks"]), []).append(r)
    out = []
    for (sweep, preset, n), rs in sorted(by.items()):
        geo = json.loads((Path(geometry_dir) / f"geometry_{sweep}_{preset}.json").read_text())
        row = next(g for g in geo["rows"] if g["ranks"] == n)
        opt = Options(pairs_per_surface_vertex=pairs_per_surface_vertex.get(sweep, 0.0), ghost_pair_weight=ghost_pairs)
        pred = step_time(row, costs, replace(net, round_trip=0.0), opt)["step_s"]
        meas = [r["step_s"] - r["phases_per_step"].get("migration", 0.0) - r["phases_per_step"].get("balance", 0.0)
                for r in rs]
        out.append({"sweep": sweep, "ranks": n, "records": len(rs), "measured_s": statistics.median(meas),
                    "predicted_s": pred, "round_trips": geometry_round_trips(geo)})
    return out


# --- costs -------------------------------------------------------------------------------

def costs_from_record(rec: dict) -> dict:
    """Per-item seconds per step from one record: a single-rank run.py record (elements /
    tets, integration / vertices, contact / candidate pairs, sph / particles), a qdemsph_bench
    record (largest run below the `largest` one: elements and integration per item) or an
    sph_bench record (sph phase per particle, largest run)."""
    c = {}
    if rec.get("program") == "qdemsph_bench":
        r = max(rec["runs"], key=lambda x: x["n_tets"])
        c["tet"] = r["elements_s_per_step"] / r["n_tets"]
        c["vertex"] = r["integration_s_per_step"] / r["n_vertices"]
        small = min(rec["runs"], key=lambda x: x["n_tets"])
        if small is not r:  # fixed cost per step: intercept of step time against size
            slope = (r["step_s"] - small["step_s"]) / (r["n_tets"] - small["n_tets"])
            c["step"] = max(0.0, small["step_s"] - slope * small["n_tets"])
        return c
    if rec.get("benchmark") == "sph_step":
        r = max(rec["runs"], key=lambda x: x["particles"])
        c["particle"] = r["sph_s"] / (r["particles"] * r["steps"])
        return c
    if rec.get("ranks", 1) != 1:
        raise ValueError("calibrate from single-rank records")
    ph, it = rec["phases_per_step"], rec["items"]
    if it.get("tets"):
        # On a GPU the Stepper's kicks and drift only launch (since 2026-11-27): their device
        # time is in "elements", so in the tet cost, and "integration" is launch time.
        c["tet"] = ph.get("elements", 0.0) / it["tets"]
        c["vertex"] = ph.get("integration", 0.0) / max(it.get("vertices", 0), 1)
    if it.get("contact_pairs"):
        c["pair"] = ph.get("contact", 0.0) / it["contact_pairs"]
        # closed triangulated surfaces: V = T / 2 + 2 per body
        surf = it.get("surface_triangles", 0) / 2 + 2 * (rec.get("size", {}).get("bodies") or 0)
        c["pairs_per_surface_vertex"] = it["contact_pairs"] / max(surf, 1)
    if it.get("particles"):
        c["particle"] = ph.get("sph", 0.0) / it["particles"]
    c["step"] = ph.get("checks", 0.0)
    return c


def calibrate(records: list[dict]) -> dict:
    """One cost set from several records: each per-item cost from the record with the most
    of that item (tets, vertices, pairs, particles)."""
    best = {}
    for rec in records:
        c = costs_from_record(rec)
        it = rec.get("items") or {}
        weight = {"tet": it.get("tets"), "vertex": it.get("vertices"), "pair": it.get("contact_pairs"),
                  "particle": it.get("particles"), "step": 1, "pairs_per_surface_vertex": it.get("contact_pairs")}
        for k, v in c.items():
            w = weight.get(k) or 1e30  # bench records: take them
            if k not in best or w > best[k][1]:
                best[k] = (v, w, rec.get("sweep") or rec.get("program") or rec.get("benchmark"))
    return {k: v for k, (v, _, _) in best.items()} | {"from": {k: s for k, (_, _, s) in best.items()}}


def load_costs(name: str) -> Costs:
    """Named cost sets (costs.json next to this file says where every number comes from)."""
    doc = json.loads((HERE / "costs.json").read_text())
    if name not in doc["costs"]:
        raise KeyError(f"unknown costs '{name}' (known: {', '.join(doc['costs'])})")
    d = doc["costs"][name]
    items = ("tet", "vertex", "pair", "particle", "step")
    missing = [k for k in items if k not in d]
    if missing:  # e.g. calibrated from a scene without fluid: no particle cost
        raise ValueError(f"costs '{name}' has no {', '.join(missing)} cost: calibrate it with records that "
                         f"have those items too (e.g. a dam-break run for the particle cost)")
    return Costs(**{k: d[k] for k in items}, label=name, source=d.get("source", ""))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("predict", help="efficiency from a geometry record")
    p.add_argument("--geometry", required=True, help="geometry.py --json output")
    p.add_argument("--costs", default="cpu-core-devvm")
    p.add_argument("--network", default="cpu-shm", choices=list(NETWORKS))
    p.add_argument("--ranks", default="1,2,4,8,16,32,64,128,256,512")
    p.add_argument("--pairs-per-surface-vertex", type=float, default=None, help="default: costs.json, by sweep")
    p.add_argument("--overlap", type=float, default=0.0)
    p.add_argument("--jitter", type=float, default=0.01)
    p.add_argument("--threshold", type=float, default=0.10, help="rebalance threshold (the stepper's default 0.10)")
    p.add_argument("--static", action="store_true", help="static partition (no rebalancing)")
    p.add_argument("--round-trips", type=int, default=None,
                   help="host round trips per step of a GPU rank (default: 4 with fluid, else 3)")
    p.add_argument("--rebuild-ms-per-step", type=float, default=0.0,
                   help="ghost / layout rebuilds during the run, amortised per step (measured: parallel "
                        "migration per step of a 2-rank record)")
    p.add_argument("--ghost-pairs", type=float, default=Options.ghost_pair_weight,
                   help="k, candidate pairs of a ghost surface vertex per owned one (0.25 measured; 0: pairs once)")
    p.add_argument("--json", help="write the prediction here")
    c = sub.add_parser("calibrate", help="per-item costs from single-rank run records / bench records")
    c.add_argument("records", nargs="+")
    c.add_argument("--name", help="store the cost set under this name in scaling/costs.json")
    c.add_argument("--source", default="", help="where the records come from (stored with the set)")
    f = sub.add_parser("fit-round-trip", help="host round trip of a GPU rank: least squares over multi-rank "
                       "records of weak sweeps, their in-run rebuilds taken out")
    f.add_argument("records", nargs="+", help="run.py records on N > 1 ranks (several of one sweep: the median)")
    f.add_argument("--costs", required=True)
    f.add_argument("--network", default="ipc-ndr", choices=list(NETWORKS))
    f.add_argument("--ghost-pairs", type=float, default=Options.ghost_pair_weight)
    f.add_argument("--geometry-dir", default=str(REPO / "references" / "benchmarks" / "scaling"))
    a = ap.parse_args(argv)
    if a.cmd == "fit-round-trip":
        ppv = json.loads((HERE / "costs.json").read_text()).get("pairs_per_surface_vertex", {})
        cases = round_trip_cases([json.loads(Path(x).read_text()) for x in a.records], load_costs(a.costs),
                                 NETWORKS[a.network], a.ghost_pairs, Path(a.geometry_dir), ppv)
        fit = fit_round_trip(cases)
        t = fit["round_trip_s"]
        print(f"costs {a.costs}, network {a.network} (its round trip set to 0), ghost pairs k {a.ghost_pairs}")
        print(f"{'sweep':15s} {'N':>2s} {'runs':>4s} {'R':>2s} {'measured':>9s} {'predicted':>9s} {'diff':>7s} "
              f"{'diff/R':>7s} {'residual':>8s}")
        for c in fit["cases"]:
            print(f"{c['sweep']:15s} {c['ranks']:2d} {c['records']:4d} {c['round_trips']:2d} "
                  f"{c['measured_s'] * 1e3:9.3f} {c['predicted_s'] * 1e3:9.3f} {c['diff_s'] * 1e3:+7.3f} "
                  f"{c['diff_s'] / c['round_trips'] * 1e6:5.0f}us {c['residual_s'] * 1e3:+8.3f}")
        print(f"(ms/step; measured: step without in-run rebuilds, median over runs; predicted: without round "
              f"trips)\nleast squares: {t * 1e6:.1f} us per round trip (now {NETWORKS[a.network].round_trip * 1e6:.1f})")
        return 0
    if a.cmd == "calibrate":
        recs = [json.loads(Path(f).read_text()) for f in a.records]
        for f, rec in zip(a.records, recs):
            print(f, json.dumps(costs_from_record(rec)))
        cal = calibrate(recs)
        print("cost set:", json.dumps(cal))
        if a.name:
            path = HERE / "costs.json"
            doc = json.loads(path.read_text()) if path.exists() else {"costs": {}}
            entry = doc["costs"].get(a.name, {})
            entry.update({k: v for k, v in cal.items() if k in ("tet", "vertex", "pair", "particle", "step")})
            entry["from"] = dict(entry.get("from", {}), **cal["from"])
            entry["records"] = sorted(set(entry.get("records", [])) | {str(Path(f)) for f in a.records})
            if a.source:
                entry["source"] = a.source
            doc["costs"][a.name] = entry
            for rec in recs:  # contact density of each case, machine-independent
                cr = costs_from_record(rec) if rec.get("sweep") else {}
                if "pairs_per_surface_vertex" in cr:
                    doc.setdefault("pairs_per_surface_vertex", {})[rec["sweep"]] = cr["pairs_per_surface_vertex"]
            path.write_text(json.dumps(doc, indent=1) + "\n")
            print(f"stored as '{a.name}' in {path}")
        return 0
    geo = json.loads(Path(a.geometry).read_text())
    costs = load_costs(a.costs)
    ranks = [int(x) for x in a.ranks.split(",")]
    rows = extend_rows(geo["rows"], ranks)
    rows = [r for r in rows if r["ranks"] in ranks]
    ppv = a.pairs_per_surface_vertex
    if ppv is None:
        ppv = json.loads((HERE / "costs.json").read_text()).get("pairs_per_surface_vertex", {}).get(geo.get("sweep") or "", 0.0)
    rt = a.round_trips
    if rt is None:
        rt = geometry_round_trips(geo)
    opt = Options(overlap=a.overlap, jitter=a.jitter, pairs_per_surface_vertex=ppv, ghost_pair_weight=a.ghost_pairs,
                  rebalance_threshold=None if a.static else a.threshold, round_trips=rt,
                  rebuild_s_per_step=a.rebuild_ms_per_step * 1e-3)
    pred = predict(rows, costs, NETWORKS[a.network], opt)
    print(f"PREDICTION (model, not a measurement): {geo.get('sweep')} ({geo.get('backend_preset')} preset), "
          f"costs {a.costs}, network {a.network}, overlap {a.overlap}, jitter {a.jitter}, ghost pairs k {a.ghost_pairs}, "
          f"round trips {rt}, rebuilds {a.rebuild_ms_per_step} ms/step, "
          f"{'static partition' if a.static else f'rebalance threshold {a.threshold}'}")
    print(f"{'N':>5} {'ms/step':>9} {'compute':>9} {'exch':>8} {'lat':>7} {'bw':>7} {'stage':>7} {'imb %':>6} {'E vs 1':>7} {'E vs 8':>7}")
    for o in pred:
        print(f"{o['ranks']:5d} {o['step_s'] * 1e3:9.3f} {o['compute_s'] * 1e3:9.3f} {o['exchange_s'] * 1e3:8.3f} "
              f"{o['latency_s'] * 1e3:7.3f} {o['bandwidth_s'] * 1e3:7.3f} {o['staging_s'] * 1e3:7.3f} "
              f"{100 * o['imbalance']:6.2f} {o.get('efficiency_vs_1', float('nan')):7.3f} "
              f"{o.get('efficiency_vs_8', float('nan')):7.3f}{'  (geometry extrapolated)' if o['extrapolated'] else ''}")
    if a.json:
        Path(a.json).write_text(json.dumps({"prediction": True, "sweep": geo.get("sweep"), "costs": asdict(costs),
                                            "network": asdict(NETWORKS[a.network]), "options": asdict(opt),
                                            "rows": pred}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
