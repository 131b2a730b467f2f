"""scaling/sfc.py against the C++ it mirrors (solver/parallel): keys, cell-tree leaves, owners
and splitters must be identical. The C++ is compiled here with g++ (sfc_driver.cpp)."""
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent))
import sfc  # noqa: E402


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    if not shutil.which("g++"):
        pytest.skip("g++ not found")
    exe = tmp_path_factory.mktemp("sfc") / "sfc_driver"
    src = REPO / "solver" / "parallel"
    subprocess.run(["g++", "-std=c++20", "-O1", "-I", str(REPO / "solver"), "-o", str(exe),
                    str(HERE / "sfc_driver.cpp"), str(src / "cell_tree.cpp"), str(src / "partition.cpp")],
                   check=True)
    return exe


def cxx(driver, text):
    return subprocess.run([str(driver)], input=text, capture_output=True, text=True, check=True).stdout.split("\n")[:-1]


@pytest.mark.parametrize("curve,order", [("morton", 3), ("hilbert", 1), ("hilbert", 3), ("hilbert", 12),
                                         ("peano", 2), ("peano", 9)])
def test_keys_match_cxx(driver, curve, order):
    rng = np.random.default_rng(order)
    side = sfc.curve_base(curve) ** order
    c = rng.integers(0, side, size=(3000, 3)) if side ** 3 > 3000 else np.indices((side,) * 3).reshape(3, -1).T
    text = f"keys {curve} {order} {len(c)}\n" + "\n".join(" ".join(map(str, r)) for r in c) + "\n"
    want = np.array(cxx(driver, text), dtype=np.uint64)
    got = sfc.keys(curve, c[:, 0], c[:, 1], c[:, 2], order)
    assert np.array_equal(got, want)


def test_hilbert_is_continuous():
    order = 3
    side = 2 ** order
    c = np.indices((side,) * 3).reshape(3, -1).T
    k = sfc.keys("hilbert", c[:, 0], c[:, 1], c[:, 2], order)
    path = c[np.argsort(k)]
    assert np.all(np.abs(np.diff(path, axis=0)).sum(axis=1) == 1)


@pytest.mark.parametrize("curve,order", [("hilbert", 5), ("peano", 3), ("morton", 4)])
def test_refine_and_partition_match_cxx(driver, curve, order):
    rng = np.random.default_rng(7)
    side = sfc.curve_base(curve) ** order
    # crowded: most items in one corner
    c = np.concatenate([rng.integers(0, side, size=(500, 3)), rng.integers(0, max(side // 4, 1), size=(1500, 3))])
    k = sfc.keys(curve, c[:, 0], c[:, 1], c[:, 2], order)
    w = rng.uniform(0.5, 2.0, size=len(k))
    items = "\n".join(f"{a} {b!r}" for a, b in zip(k, w))
    max_cost = 0.02 * w.sum() / 7
    lines = cxx(driver, f"refine {curve} {order} {max_cost!r} 1 {len(k)}\n{items}\n")
    want = np.array([ln.split() for ln in lines], dtype=float)
    lk, ls, ll, lc = sfc.refine_cells(curve, order, k, w, max_cost, 1)
    assert len(lk) == len(want)
    assert np.array_equal(lk, np.array([ln.split()[0] for ln in lines], dtype=np.uint64))
    assert np.array_equal(ls, np.array([ln.split()[1] for ln in lines], dtype=np.uint64))
    assert np.array_equal(ll, want[:, 2].astype(int))
    assert np.allclose(lc, want[:, 3], rtol=1e-14, atol=1e-12)
    for nranks in (1, 3, 7, 64):
        cells = "\n".join(f"{a} {b!r}" for a, b in zip(lk, lc))
        out = cxx(driver, f"part {nranks} {len(lk)}\n{cells}\n")
        owner = sfc.partition_cells(lc, nranks)
        assert np.array_equal(owner, np.array(out[:len(lk)], dtype=int))
        split = sfc.partition_splitters(lk, owner, nranks)
        assert np.array_equal(split, np.array(out[len(lk):], dtype=np.uint64))
        # every leaf's first key maps back to its owner; the cut bound holds
        assert np.array_equal(sfc.owner_of_key(split, lk), owner)
        st = sfc.partition_stats(lc, owner, nranks)
        assert np.all(np.abs(st["load"] - st["mean"]) <= lc.max() + 1e-9)
