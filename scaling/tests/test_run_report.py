"""Runner helpers (scaling/run.py) and report arithmetic (scaling/report.py)."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import report  # noqa: E402
import run  # noqa: E402


def test_mpirun_binding_and_flags():
    cmd, env, facts = run.launch_command("mpirun", 4, 1, "cpu", cores=16, root=True, extra=[])
    assert cmd[:3] == ["mpirun", "-np", "4"] and "--allow-run-as-root" in cmd
    assert cmd[cmd.index("--bind-to") + 1] == "core" and "--oversubscribe" not in cmd
    assert env["OMP_NUM_THREADS"] == "1" and "OMP_NUM_THREADS=1" in cmd
    cmd, _, facts = run.launch_command("mpirun", 2, 8, "cuda", cores=16, root=False, extra=[])
    assert "slot:PE=8" in cmd and "--allow-run-as-root" not in cmd
    cmd, _, facts = run.launch_command("mpirun", 32, 1, "cpu", cores=16, root=False, extra=[])
    assert "--oversubscribe" in cmd and facts["oversubscribed"]
    cmd, _, facts = run.launch_command("srun", 8, 4, "cuda", cores=64, root=False, extra=[])
    assert cmd[:3] == ["srun", "-n", "8"] and "--gpus-per-task=1" in cmd and "--cpus-per-task=4" in cmd
    with pytest.raises(ValueError):
        run.launch_command("none", 2, 1, "cpu", cores=4, root=False, extra=[])


def test_host_usage_counts_a_childs_page_faults_and_cpu_time():
    import subprocess
    u0 = run.host_usage()
    # A child that touches 64 MB of fresh memory: at least that many 4 KiB pages faulted in.
    subprocess.run([sys.executable, "-c", "b = b'x' * (64 << 20)"], check=True)
    u = run.usage_between(u0, run.host_usage())
    assert u["minor_faults"] >= (64 << 20) // 4096
    assert u["user_s"] + u["sys_s"] > 0 and u["major_faults"] >= 0
    assert u.get("steal_s", 0) >= 0


def test_step_seconds_prefers_the_rank_mean_and_drops_output_and_subphases():
    # In-run migration and balance are part of the step; the first distribution (setup_s) is not.
    s = {"steps": 10, "phases": {"elements": 5.0, "output": 9.0},
         "parallel": {"phases_mean": {"elements": 1.0, "contact": 0.5, "contact.broad": 0.2, "halo": 0.5,
                                      "output": 3.0, "migration": 0.4, "balance": 0.1},
                      "phases_max": {"elements": 1.2, "contact": 0.5, "halo": 0.6, "output": 3.0, "migration": 1.0},
                      "setup_s": 0.3}}
    t = run.step_seconds(s)
    assert t["step_s"] == pytest.approx(0.25) and t["phase_source"] == "parallel.phases_mean"
    assert t["step_s_all"] == pytest.approx(0.28) and t["setup_s"] == pytest.approx(0.3)
    assert t["step_s_maxsum"] == pytest.approx(0.33)
    serial = run.step_seconds({"steps": 4, "phases": {"elements": 2.0, "output": 1.0, "contact.narrow": 1.0}})
    assert serial["step_s"] == pytest.approx(0.5)


def test_busy_imbalance_counts_the_fluid_passes_not_the_waits():
    # Rank 1 waits for rank 0 in the halo; the fluid's passes make the difference.
    par = {"imbalance": 0.01,
           "phases_by_rank": [{"elements": 0.1, "sph": 4.4, "halo": 0.2, "migration": 0.3, "output": 7.0},
                              {"elements": 0.1, "sph": 4.0, "halo": 0.6, "migration": 0.3, "output": 7.0}]}
    assert run.busy_imbalance(par) == pytest.approx(4.5 / 4.3 - 1)
    assert run.busy_imbalance({"phases_by_rank": [{"elements": 1.0}]}) == 0.0
    assert run.busy_imbalance({}) is None


def rec(n, step_s, mode="weak"):
    return {"ranks": n, "step_s": step_s, "mode": mode, "size": {"n_tets": n, "n_particles": 0},
            "imbalance": None, "halo_bytes_per_step": None}


def test_weak_efficiency_against_1_and_8_ranks():
    rows = report.efficiencies([rec(1, 1.0), rec(8, 1.25), rec(64, 1.6)], "weak")
    assert rows[1]["E1"] == pytest.approx(0.8)
    assert rows[2]["E1"] == pytest.approx(1 / 1.6) and rows[2]["E8"] == pytest.approx(1.25 / 1.6)
    assert "E8" not in rows[0]


def test_pairs_a_rank_against_one_rank():
    def with_pairs(n, pairs):
        return {**rec(n, 1.0), "items": {"contact_pairs": pairs}}

    rows = report.efficiencies([with_pairs(1, 1000), with_pairs(2, 2068), rec(4, 1.2)], "weak")
    assert rows[0]["pairs_ratio"] == pytest.approx(1.0) and rows[1]["pairs_ratio"] == pytest.approx(1.034)
    assert "pairs_ratio" not in rows[2]  # no contact pairs in that record


def test_strong_efficiency():
    rows = report.efficiencies([rec(1, 8.0, "strong"), rec(4, 2.5, "strong")], "strong")
    assert rows[1]["E1"] == pytest.approx(8.0 / (4 * 2.5)) and rows[1]["speedup"] == pytest.approx(3.2)


def test_a_series_without_1_or_8_ranks_is_plotted_against_its_fewest():
    pytest.importorskip("matplotlib")

    def run_of(n, step):
        return {**rec(n, step, "strong"), "status": "ok", "sweep": "slide-balance", "backend": "cuda",
                "variant": "static", "date": "2026-01-01", "machine": {"revision": "a"},
                "phases_per_step": {"contact": step}}

    figs, md = report.plots([run_of(2, 2.0), run_of(4, 1.25)])
    assert figs and any("| 4 |" in line for line in md)


def test_fluid_halo_bytes_reach_the_table_rows():
    rows = report.efficiencies([{**rec(2, 1.0), "fluid_halo_bytes_per_step": 2.5e6}, rec(4, 1.1)], "weak")
    assert rows[0]["fluid_halo_bytes_per_step"] == 2.5e6 and rows[1]["fluid_halo_bytes_per_step"] is None


def test_a_series_row_is_the_median_run_of_the_newest_revision():
    def run_of(rev, date, step):
        return {"status": "ok", "step_s": step, "sweep": "cubes-weak", "backend": "cuda", "ranks": 2,
                "date": date, "machine": {"revision": rev}}

    old = [run_of("a", "2026-01-01T00:00:0" + str(i), s) for i, s in enumerate((0.5, 0.6, 0.7))]
    new = [run_of("b", "2026-01-02T00:00:0" + str(i), s) for i, s in enumerate((3.0, 1.0, 2.0, 9.0))]
    (rows,) = report.series(old + new).values()
    assert [r["step_s"] for r in rows] == [2.0]  # b's four runs: the faster of the middle two
    assert rows[0]["step_s_runs"] == [1.0, 2.0, 3.0, 9.0]
    assert report.spread(rows[0]["step_s_runs"]) == "4: 1000.00-9000.00" and report.spread([1.0]) == "1"
    (rows,) = report.series(old).values()
    assert [r["step_s"] for r in rows] == [0.6]


def test_a_series_keeps_one_revision_and_its_own_baselines():
    def run_of(n, rev, date, step):
        return {**rec(n, step), "status": "ok", "sweep": "dambreak-weak", "backend": "cuda",
                "variant": "v", "date": date, "machine": {"revision": rev},  # a variant: no model line
                "phases_per_step": {"sph": step}}

    # A call interleaving a build "b" with an experiment on "a" ("a+exp") that ran last at four
    # ranks, and an older call of "a" alone at eight.
    recs = [run_of(1, "b", "2026-01-02T00:00:01", 3.4), run_of(1, "a+exp", "2026-01-02T00:00:02", 3.6),
            run_of(4, "b", "2026-01-02T00:00:03", 4.8), run_of(4, "a+exp", "2026-01-02T00:00:04", 4.9),
            run_of(1, "a", "2026-01-01T00:00:00", 3.6), run_of(8, "a", "2026-01-01T00:00:01", 5.0)]
    assert report.newest_revision(recs) == "b"  # a build before an experiment run after it
    assert report.newest_revision([r for r in recs if r["machine"]["revision"] == "a+exp"]) == "a+exp"
    (rs,) = report.series(recs).values()
    assert [(r["ranks"], r["machine"]["revision"]) for r in rs] == [(1, "b"), (4, "b"), (8, "a")]
    rows = report.efficiencies(rs, "weak")
    assert rows[1]["E1"] == pytest.approx(3.4 / 4.8) and rows[1]["other_ref"] == []  # not a+exp's
    assert rows[2]["revision"] == "a" and rows[2]["other_ref"] == [1]  # b's one-rank run: marked
    _, md = report.plots(recs)
    assert any(line.startswith("| 8 |") and "†" in line and "| a |" in line for line in md)


def test_node_factor_only_from_copies_of_the_same_revision():
    def run_of(n, step, rev):
        return {**rec(n, step), "machine": {"revision": rev}}

    rs = [run_of(1, 1.0, "b"), run_of(2, 1.5, "b"), run_of(4, 2.0, "b")]
    rows = report.efficiencies(rs, "weak")
    report.node_factors(rows, rs, [run_of(2, 1.25, "b"), run_of(4, 3.0, "a")])
    assert rows[1]["node"] == pytest.approx(0.8) and rows[1]["decomp"] == pytest.approx(1.25 / 1.5)
    assert "node" not in rows[2]  # copies of revision a: not this code's baseline
    assert "node" not in rows[0]  # no copies at one rank


def test_preset_values_can_be_overridden_and_keep_their_own_series():
    import scenes

    assert scenes.parse_params(["cubes_per_rank=864", "cells=8"]) == {"cubes_per_rank": 864, "cells": 8}
    assert run.params_tag({"cubes_per_rank": 864}) == "_cubes_per_rank-864" and run.params_tag({}) == ""
    with pytest.raises(ValueError):
        scenes.parse_params(["cubes_per_rank"])
    big = scenes.scene_for("cubes-weak", 1, "cpu", params={"cubes_per_rank": 54})[1]
    assert big["n_tets"] == 2 * scenes.scene_for("cubes-weak", 1, "cpu")[1]["n_tets"]
    assert big["params"] == {"cubes_per_rank": 54} and big["preset_params"]["cubes_per_rank"] == 54
    with pytest.raises(KeyError, match="no parameter bogus"):
        scenes.scene_for("cubes-weak", 1, "cpu", params={"bogus": 1})
    base = {"status": "ok", "step_s": 1.0, "sweep": "cubes-weak", "backend": "cuda", "ranks": 1, "date": "x",
            "machine": {}}
    ser = report.series([base, dict(base, params={"cubes_per_rank": 864})])
    assert len(ser) == 2 and any(k[4] == "cubes_per_rank=864" for k in ser)


def test_revision_is_the_packs_the_binary_comes_from(tmp_path, monkeypatch):
    monkeypatch.delenv("QDEMSPH_REVISION", raising=False)
    (tmp_path / "bin").mkdir()
    binary = tmp_path / "bin" / "qdemsph"
    binary.write_text("")
    checkout = run.revision_of(str(binary))  # no REVISION beside it: this checkout's
    (tmp_path / "REVISION").write_text("abc1234\n")
    assert run.revision_of(str(binary)) == "abc1234"
    assert checkout != "abc1234"
    monkeypatch.setenv("QDEMSPH_REVISION", "def5678")
    assert run.revision_of(str(binary)) == "def5678"
