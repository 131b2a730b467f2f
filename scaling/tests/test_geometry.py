"""Partition geometry (scaling/geometry.py) and scene generators (scaling/scenes.py)."""
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent))
import geometry  # noqa: E402
import scenes  # noqa: E402

QDEMSPH = REPO / "build" / "bin" / "qdemsph"


def test_box_mesh_is_the_report_cube():
    p, t = geometry.box_mesh((0, 0, 0), (1, 1, 1), (8, 8, 8))
    assert len(p) == 1241 and len(t) == 6144
    a, b, c, d = (p[t[:, k]] for k in range(4))
    vol = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6
    assert np.all(np.abs(vol) > 0)
    assert np.sum(np.abs(vol)) == pytest.approx(1.0)
    # conforming: every interior triangle is shared by exactly two tets
    faces = np.sort(np.concatenate([t[:, [0, 1, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 3]], t[:, [1, 2, 3]]]), axis=1)
    _, counts = np.unique(faces, axis=0, return_counts=True)
    assert set(counts) == {1, 2} and np.sum(counts == 1) == 768  # 6 faces x 64 hex faces x 2 triangles


@pytest.mark.parametrize("sweep,n", [("cubes-weak", 2), ("dambreak-weak", 3), ("topple-weak", 1), ("dambreak-balance", 4)])
def test_scene_sizes_match_the_items(sweep, n):
    scene, meta = scenes.scene_for(sweep, n, "cpu")
    it = geometry.SceneItems(scene)
    assert len(it.vertices) == meta["n_vertices"]
    assert it.n_tets == meta["n_tets"]
    assert len(it.particles) == meta["n_particles"]


@pytest.mark.skipif(not QDEMSPH.exists(), reason="build/bin/qdemsph not built")
@pytest.mark.parametrize("sweep", ["cubes-weak", "dambreak-weak", "topple-weak"])
def test_scene_sizes_match_the_solver(sweep, tmp_path):
    scene, meta = scenes.scene_for(sweep, 1, "cpu")
    f = tmp_path / "s.yaml"
    f.write_text(scenes.dump(scene))
    info = subprocess.run([str(QDEMSPH), "info", str(f)], capture_output=True, text=True, check=True).stdout
    if meta["n_tets"]:
        m = re.search(r"sizes\s+(\d+) vertices, (\d+) tets", info)
        assert (int(m.group(1)), int(m.group(2))) == (meta["n_vertices"], meta["n_tets"])
    if meta["n_particles"]:
        m = re.search(r"SPH \((\d+) fluid \+ (\d+) wall", info)
        assert int(m.group(1)) + int(m.group(2)) == meta["n_particles"]


def test_weak_scenes_grow_with_ranks():
    for sweep in ("cubes-weak", "dambreak-weak", "topple-weak"):
        m1 = scenes.scene_for(sweep, 1, "cpu")[1]
        m8 = scenes.scene_for(sweep, 8, "cpu")[1]
        assert m8["items"] == pytest.approx(8 * m1["items"], rel=0.02), sweep


def test_partition_geometry_invariants():
    scene, _ = scenes.scene_for("cubes-weak", 1, "cpu")
    g1 = geometry.partition_geometry(scene, 1)
    assert g1["ghost_vertices"].sum() == 0 and g1["held_tets"][0] == g1["n_tets"]
    for n in (2, 5):
        g = geometry.partition_geometry(scene, n)
        assert g["owned_vertices"].sum() == g["n_vertices"]
        assert g["home_tets"].sum() == g["n_tets"]
        assert g["held_tets"].sum() >= g["n_tets"]
        # the band (everything within L_cell of another rank) holds every needed ghost
        assert np.all(g["needed_ghost_vertices"] <= g["ghost_vertices"])
        assert np.all(g["recv_neighbours"] >= 1)


def test_two_distant_blocks_need_no_halo():
    scene, _ = scenes.cube_block(2, cells=2)
    scene["bodies"] = [b for b in scene["bodies"] if b["mesh"]["origin"][2] < 0.5]
    scene["bodies"][1]["mesh"]["origin"][0] = 50.0
    g = geometry.partition_geometry(scene, 2)
    assert list(g["ghost_vertices"]) == [0, 0] and list(g["held_tets"]) == list(g["home_tets"])
