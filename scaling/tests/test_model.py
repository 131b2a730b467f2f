"""Known answers of the performance model (scaling/model.py)."""
import json
import math
import sys
from dataclasses import replace
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import model  # noqa: E402

COSTS = model.Costs(tet=1e-9, vertex=1e-9, pair=0.0, particle=1e-8, step=0.0)
NET = model.Network("t", intra_latency=1e-6, intra_bandwidth=1e9, inter_latency=2e-6, inter_bandwidth=1e8,
                    ranks_per_node=4)
NOJIT = model.Options(jitter=0.0, allreduces=0, rebalance_threshold=None)


def rows(ns, tets=1000, verts=200, ghosts=50, nbrs=2, extra_tets=0):
    """Uniform synthetic geometry: every rank the same counts."""
    out = []
    for n in ns:
        out.append({"ranks": n, "held_tets": [tets + (extra_tets if n > 1 else 0)] * n,
                    "owned_vertices": [verts] * n, "ghost_vertices": [ghosts if n > 1 else 0] * n,
                    "recv_neighbours": [nbrs if n > 1 else 0] * n})
    return out


def test_no_communication_cost_gives_efficiency_one():
    ideal = model.NETWORKS["ideal"]
    pred = model.predict(rows([1, 2, 8, 512]), COSTS, ideal, NOJIT)
    for p in pred:
        assert p["efficiency_vs_1"] == pytest.approx(1.0, abs=1e-12)
    assert pred[-1]["efficiency_vs_8"] == pytest.approx(1.0, abs=1e-12)


def test_compute_term_is_items_times_cost():
    p = model.step_time(rows([1])[0], COSTS, NET, NOJIT)
    assert p["step_s"] == pytest.approx(1000 * 1e-9 + 200 * 1e-9)


def test_doubling_bandwidth_halves_the_bandwidth_time():
    net0 = replace(NET, intra_latency=0.0)
    g = rows([4])[0]
    t1 = model.step_time(g, COSTS, net0, NOJIT)
    t2 = model.step_time(g, COSTS, replace(net0, intra_bandwidth=2e9), NOJIT)
    assert t1["bandwidth_s"] == pytest.approx(NOJIT.exchanges * 50 * NOJIT.vertex_bytes / 1e9)
    assert t2["bandwidth_s"] == pytest.approx(t1["bandwidth_s"] / 2)
    assert t2["exchange_s"] == pytest.approx(t1["exchange_s"] / 2)


def test_latency_term_counts_messages():
    net = replace(NET, intra_bandwidth=math.inf)
    p = model.step_time(rows([4], nbrs=3)[0], COSTS, net, NOJIT)
    assert p["exchange_s"] == pytest.approx(NOJIT.exchanges * 3 * 1e-6)


def test_off_node_traffic_uses_the_inter_node_network():
    g = rows([8])[0]
    g["ghost_vertices_offnode_rpn4"] = [20] * 8
    g["recv_neighbours_offnode_rpn4"] = [1] * 8
    net = replace(NET, stage_bandwidth=0.0)
    p = model.step_time(g, COSTS, net, NOJIT)
    vb = NOJIT.vertex_bytes
    want = NOJIT.exchanges * (1 * 1e-6 + 1 * 2e-6 + 30 * vb / 1e9 + 20 * vb / 1e8)
    assert p["exchange_s"] == pytest.approx(want)


def test_staging_adds_two_copies_per_exchange():
    net = replace(NET, intra_latency=0.0, intra_bandwidth=math.inf, stage_latency=1e-5, stage_bandwidth=1e9)
    p = model.step_time(rows([2])[0], COSTS, net, NOJIT)
    assert p["staging_s"] == pytest.approx(NOJIT.exchanges * 2 * (1e-5 + 50 * NOJIT.vertex_bytes / 1e9))


def test_imbalance_sets_the_step():
    g = rows([4])[0]
    g["held_tets"] = [1000, 1000, 1000, 1400]
    p = model.step_time(g, COSTS, model.NETWORKS["ideal"], NOJIT)
    assert p["step_s"] == pytest.approx(1400e-9 + 200e-9)
    assert p["critical_rank"] == 3
    assert p["imbalance"] == pytest.approx(1600 / 1300 - 1)


def test_balancer_evens_out_an_imbalance_above_its_threshold():
    g = rows([4])[0]
    g["held_tets"] = [1000, 1000, 1000, 1400]  # static imbalance 1600/1300 - 1 = 23 %
    g["imbalance_partition"] = 0.01
    ideal = model.NETWORKS["ideal"]
    p = model.step_time(g, COSTS, ideal, replace(NOJIT, rebalance_threshold=0.10))
    assert p["rebalanced"] and p["step_s"] == pytest.approx(1300e-9 * 1.01)
    q = model.step_time(g, COSTS, ideal, replace(NOJIT, rebalance_threshold=0.30))  # below: kept
    assert not q["rebalanced"] and q["step_s"] == pytest.approx(1600e-9)


def test_redundant_halo_tets_cost_efficiency():
    pred = model.predict(rows([1, 2], extra_tets=100), COSTS, model.NETWORKS["ideal"], NOJIT)
    assert pred[1]["efficiency_vs_1"] == pytest.approx(1200 / 1300)


def test_full_overlap_hides_communication_shorter_than_compute():
    opt = replace(NOJIT, overlap=1.0)
    g = rows([2], tets=100_000)[0]  # compute 1e-4 s > exchange 4e-6 s
    p = model.step_time(g, COSTS, replace(NET, intra_bandwidth=1e12), opt)
    assert p["exchange_raw_s"] > 0 and p["exchange_s"] == 0.0
    half = model.step_time(g, COSTS, replace(NET, intra_bandwidth=1e12), replace(NOJIT, overlap=0.0))
    assert half["exchange_s"] == pytest.approx(p["exchange_raw_s"])


def test_jitter_is_the_gaussian_extreme_value():
    opt = replace(NOJIT, jitter=0.02)
    ideal = model.NETWORKS["ideal"]
    p1 = model.step_time(rows([1])[0], COSTS, ideal, opt)
    p64 = model.step_time(rows([64])[0], COSTS, ideal, opt)
    assert p1["jitter_s"] == 0.0
    assert p64["step_s"] == pytest.approx(1.2e-6 * (1 + 0.02 * math.sqrt(2 * math.log(64))))


def test_allreduce_is_log2_latency():
    opt = replace(NOJIT, allreduces=2)
    net = replace(NET, intra_bandwidth=math.inf, intra_latency=0.0, inter_bandwidth=math.inf)
    g = rows([16], nbrs=0)[0]
    p = model.step_time(g, COSTS, net, opt)
    assert p["allreduce_s"] == pytest.approx(2 * 4 * 2e-6)  # 16 ranks > 4 per node: inter latency


def test_allreduce_on_a_node_takes_the_host_latency_where_halos_are_device_copies():
    opt = replace(NOJIT, allreduces=2)
    net = replace(NET, intra_bandwidth=math.inf, intra_latency=8e-6, inter_bandwidth=math.inf, host_latency=0.5e-6)
    p = model.step_time(rows([4], nbrs=0)[0], COSTS, net, opt)
    assert p["allreduce_s"] == pytest.approx(2 * 2 * 0.5e-6)  # 4 ranks on one node: log2 4 = 2 stages


def test_extrapolated_rows_take_the_slowest_candidate():
    g = rows([1, 16, 32])
    g[1]["held_tets"] = [1000] * 15 + [1500]  # the worst piece of N=16 is worse than N=32's
    ext = model.extend_rows(g, [1, 16, 32, 64])
    assert [r["ranks"] for r in ext] == [1, 16, 32, 64] and ext[3]["extrapolated"]
    p = model.step_time(ext[3], COSTS, model.NETWORKS["ideal"], NOJIT)
    assert p["ranks"] == 64 and p["geometry_from_ranks"] == 16
    assert p["step_s"] == pytest.approx(1500e-9 + 200e-9)
    with pytest.raises(ValueError):
        model.extend_rows(g, [8])


def test_costs_from_record():
    rec = {"ranks": 1, "phases_per_step": {"elements": 2.0, "integration": 0.5, "contact": 3.0, "sph": 0.0,
                                           "checks": 0.1},
           "items": {"tets": 1000, "vertices": 250, "contact_pairs": 600, "particles": 0, "surface_triangles": 100},
           "size": {"bodies": 3}}
    c = model.costs_from_record(rec)
    assert c["tet"] == pytest.approx(2e-3) and c["vertex"] == pytest.approx(2e-3)
    assert c["pair"] == pytest.approx(5e-3)
    assert c["pairs_per_surface_vertex"] == pytest.approx(600 / (100 / 2 + 2 * 3))
    assert c["step"] == pytest.approx(0.1)


def test_named_cost_sets_load():
    c = model.load_costs("h200")
    assert c.tet > 0 and c.particle > 0


def test_a_cost_set_without_an_item_cost_is_refused_by_name(tmp_path, monkeypatch):
    (tmp_path / "costs.json").write_text(json.dumps(
        {"costs": {"bodies-only": {"tet": 1e-11, "vertex": 5e-11, "pair": 5e-10, "step": 0.0}}}))
    monkeypatch.setattr(model, "HERE", tmp_path)
    with pytest.raises(ValueError, match="'bodies-only' has no particle cost"):
        model.load_costs("bodies-only")


def test_contact_work_counts_owned_and_ghost_surface():
    g = rows([2], tets=0, verts=0)[0]
    g["owned_surface_vertices"] = [100, 100]
    g["ghost_surface_vertices"] = [30, 10]
    c = model.Costs(tet=0.0, vertex=0.0, pair=1e-6, particle=0.0)
    p = model.step_time(g, c, model.NETWORKS["ideal"], replace(NOJIT, pairs_per_surface_vertex=20.0, ghost_pair_weight=1.0))
    assert p["compute_s"] == pytest.approx(130 * 20 * 1e-6)
    q = model.step_time(g, c, model.NETWORKS["ideal"], replace(NOJIT, pairs_per_surface_vertex=20.0, ghost_pair_weight=0.0))
    assert q["compute_s"] == pytest.approx(100 * 20 * 1e-6)


def test_host_round_trips_add_a_fixed_time_per_step():
    net = replace(NET, intra_latency=0.0, intra_bandwidth=math.inf, round_trip=1.5e-4)
    g = rows([2])[0]
    none = model.step_time(g, COSTS, net, NOJIT)
    three = model.step_time(g, COSTS, net, replace(NOJIT, round_trips=3))
    assert none["round_trip_s"] == 0.0
    assert three["round_trip_s"] == pytest.approx(4.5e-4)
    assert three["step_s"] - none["step_s"] == pytest.approx(4.5e-4)
    one_rank = model.step_time(rows([1])[0], COSTS, net, replace(NOJIT, round_trips=3))
    assert one_rank["step_s"] == pytest.approx(1000 * 1e-9 + 200 * 1e-9)  # no exchange on one rank
    assert model.round_trips(True) == 4 and model.round_trips(False) == 3


def test_device_resident_halos_stage_only_what_leaves_the_node_and_rebuilds_add_per_step():
    staged = replace(NET, stage_latency=1e-5, stage_bandwidth=1e9)
    g = rows([2])[0]
    on_node = model.step_time(g, COSTS, staged, NOJIT)
    assert on_node["staging_s"] > 0  # host staging of every halo byte
    ipc = model.step_time(g, COSTS, replace(staged, stage_offnode_only=True), NOJIT)
    assert ipc["staging_s"] == 0.0  # both ranks on one node: nothing crosses PCIe
    reb = model.step_time(g, COSTS, NET, replace(NOJIT, rebuild_s_per_step=1.6e-3))
    assert reb["step_s"] - model.step_time(g, COSTS, NET, NOJIT)["step_s"] == pytest.approx(1.6e-3)
    one_rank = model.step_time(rows([1])[0], COSTS, NET, replace(NOJIT, rebuild_s_per_step=1.6e-3))
    assert one_rank["rebuild_s"] == 0.0  # one rank rebuilds nothing


def test_round_trip_is_the_least_squares_over_the_cases():
    # d = 0.2 ms over 3 round trips and 0.5 ms over 4: t = (3 x 0.2 + 4 x 0.5) / (9 + 16) = 0.104 ms
    cases = [{"measured_s": 1.2e-3, "predicted_s": 1.0e-3, "round_trips": 3},
             {"measured_s": 4.5e-3, "predicted_s": 4.0e-3, "round_trips": 4}]
    f = model.fit_round_trip(cases)
    assert f["round_trip_s"] == pytest.approx(1.04e-4)
    assert [c["diff_s"] for c in f["cases"]] == pytest.approx([2e-4, 5e-4])
    assert [c["residual_s"] for c in f["cases"]] == pytest.approx([2e-4 - 3.12e-4, 5e-4 - 4.16e-4])


def test_round_trip_cases_take_out_rebuilds_and_round_trips(tmp_path):
    (tmp_path / "geometry_s_cuda.json").write_text(json.dumps({"rows": rows([1, 2])}))
    # steps less migration and balance: 2.0, 2.2, 2.2 ms -> median 2.2
    recs = [{"sweep": "s", "preset": "cuda", "ranks": 2, "step_s": t, "phases_per_step": {"migration": m, "balance": b}}
            for t, m, b in [(3.0e-3, 1.0e-3, 0.0), (2.5e-3, 0.2e-3, 0.1e-3), (2.2e-3, 0.0, 0.0)]]
    net = replace(model.NETWORKS["ideal"], round_trip=1e-4)  # not in the prediction
    (c,) = model.round_trip_cases(recs, COSTS, net, 0.0, tmp_path, {})
    assert c["records"] == 3 and c["round_trips"] == 3  # no particles: bodies
    assert c["measured_s"] == pytest.approx(2.2e-3)
    jitter = 0.01 * math.sqrt(2 * math.log(2))  # Options' default s; ideal: no exchange, no allreduce
    assert c["predicted_s"] == pytest.approx((1000 + 200) * 1e-9 * (1 + jitter))


def test_ipc_round_trip_is_the_fit_of_its_records():
    """IPC_ROUND_TRIP is what `model.py fit-round-trip` gives on the records its comment names
    (a cost set, geometry or option change that moves it means: fit it again)."""
    d = model.REPO / "references" / "benchmarks" / "scaling" / "2026-11-27_x4_pool_merge" / "call4_h200x4"
    files = [d / f"N_{s}_r{i}/records/{s}_cuda_n{n}.json" for s, rounds in
             (("cubes-weak", (1,)), ("dambreak-weak", (1, 2)), ("topple-weak", (1, 2)))
             for i in rounds for n in (2, 4)]
    if not all(f.exists() for f in files):
        pytest.skip("records not present")
    ppv = json.loads((model.HERE / "costs.json").read_text())["pairs_per_surface_vertex"]
    cases = model.round_trip_cases([json.loads(f.read_text()) for f in files], model.load_costs("h200-05319f8"),
                                   model.NETWORKS["ipc-ndr"], model.Options.ghost_pair_weight,
                                   model.REPO / "references" / "benchmarks" / "scaling", ppv)
    assert [c["round_trips"] for c in cases] == [3, 3, 4, 4, 3, 3]  # cubes, dam break, dominoes at 2, 4
    assert model.fit_round_trip(cases)["round_trip_s"] == pytest.approx(model.IPC_ROUND_TRIP, abs=0.5e-6)
    assert model.NETWORKS["ipc-ndr"].round_trip == model.IPC_ROUND_TRIP
