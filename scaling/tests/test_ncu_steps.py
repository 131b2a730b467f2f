"""ncu_steps.py: kernel groups, the window cut to whole steps, busy time per step."""
import gzip
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import ncu_steps  # noqa: E402

HEADER = '"ID","Kernel Name","Metric Name","Metric Unit","Metric Value"\n'
ASSEMBLE = ("void cuda_detail::for_each_kernel<1, qdemsph::QdemBackend<qdemsph::CudaExec>::"
            "assemble_forces(double, double)::[lambda(long) (instance 1)]>(long, T2)")
NARROW = ("void cuda_detail::for_each_kernel<2, qdemsph::ContactStage<qdemsph::CudaExec>::"
          "narrow_phase(qdemsph::Vec3ViewT<const double>)::[lambda(long) (instance 2)]>(long, T2)")
SORT = "void merge_sort::DeviceMergeSortMergeKernel<merge_sort::policy_hub<qdemsph::ContactRecord *>>(bool)"


def write(path, kernels):
    lines = ["==PROF== Connected to process 1\n", HEADER]
    for i, (name, ns) in enumerate(kernels):
        lines.append(f'"{i}","{name}","gpu__time_duration.sum","ns","{ns:,}"\n')
    with gzip.open(path, "wt") as f:
        f.writelines(lines)


def test_groups_name_the_lambdas_function_or_the_cub_kernel():
    assert ncu_steps.group(ASSEMBLE) == "assemble_forces#1"
    assert ncu_steps.group(NARROW) == "narrow_phase#2"
    assert ncu_steps.group(SORT) == "cub:DeviceMergeSortMergeKernel"


def test_the_window_is_cut_to_whole_steps(tmp_path):
    # A partial step, three whole ones (assemble, narrow, two sort passes), a partial one.
    step = [(ASSEMBLE, 100_000), (NARROW, 800_000), (SORT, 50_000), (SORT, 50_000)]
    write(tmp_path / "k.csv.gz", [(SORT, 9_000_000)] + 3 * step + [(ASSEMBLE, 100_000), (NARROW, 9_000_000)])
    steps, us, calls = ncu_steps.per_step(ncu_steps.read(str(tmp_path / "k.csv.gz")), "assemble_forces")
    assert steps == 3
    assert us["narrow_phase#2"] == pytest.approx(800.0) and us["cub:DeviceMergeSortMergeKernel"] == pytest.approx(100.0)
    assert calls["cub:DeviceMergeSortMergeKernel"] == pytest.approx(2.0)
    assert sum(us.values()) == pytest.approx(1000.0)
    with pytest.raises(ValueError, match="marker"):
        ncu_steps.per_step(ncu_steps.read(str(tmp_path / "k.csv.gz")), "no_such_kernel")


def test_idle_is_the_step_less_the_busy_time(tmp_path, capsys):
    step = [(ASSEMBLE, 100_000), (NARROW, 800_000)]
    write(tmp_path / "k.csv.gz", 3 * step + [(ASSEMBLE, 100_000)])
    assert ncu_steps.main([str(tmp_path / "k.csv.gz"), "--step-ms", "1.2"]) == 0
    out = capsys.readouterr().out
    assert "| **busy** | **900.0** |" in out and "| **idle** | **300.0** |" in out
