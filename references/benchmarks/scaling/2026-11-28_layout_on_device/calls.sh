#!/bin/bash
# The device calls of this folder (README.md), as they ran: `bash calls.sh callN` in the
# repository root of a device machine, with the packs of README's table carried as
# build-pack-<pack> (helpers: scaling/device_calls.sh).
. scaling/device_calls.sh

# The packs: ce1dc5e (sd, the fluid layout before); 62af779 (lg: the layout's fields gathered
# on the device, the halo's device buffers mapped again only where they grow); 8d56b03 (hc: lg
# with the bounced copies' host side on the threads); 0009c56 (so: hc with the key-order sort
# on the device). Calls 2-4 carried the test binaries as bin/tests.tgz (the carry's size).
packs() {
  wrapper sd sd ce1dc5e
  wrapper lg lg 62af779
  wrapper hc hc 8d56b03
  wrapper so so 0009c56
}

# Call 1 (4 x H200): lg's distributed GPU tests (the pack carried without qdemsph_tests: the
# carry's size); the two- and four-GPU fluid.csv of sd and lg compared; the dam
# break at one, two and four GPUs, sd and lg interleaved.
call1() {
  packs
  (cd build-pack-lg && LD_LIBRARY_PATH=$PWD/lib mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests \
    --gtest_filter='DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*' >$R/gputests_mpi.log 2>&1)
  echo "mpi tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_mpi.log | tail -2 | tr '\n' ' ')"
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for n in 2 4; do
    for w in sd lg; do run D${n}_${w}_r1 dambreak-weak $n $w - --keep; done
    echo "cmp $n-GPU fluid.csv sd vs lg: $(cmp $R/D${n}_sd_r1/runs/*/fluid.csv $R/D${n}_lg_r1/runs/*/fluid.csv && echo identical)"
  done
  for r in 1 2 3; do
    for w in sd lg; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      [ $r -gt 1 ] && run D2_${w}_r$r dambreak-weak 2 $w -
      [ $r -gt 1 ] && run D4_${w}_r$r dambreak-weak 4 $w -
    done
  done
  for w in sd lg; do run D2_${w}_r4 dambreak-weak 2 $w -; run D4_${w}_r4 dambreak-weak 4 $w -; done
}

# Call 2 (4 x H200): hc's tests; the two- and four-GPU fluid.csv of sd and hc compared; the dam
# break at one, two and four GPUs and the dominoes at two and four, sd and hc interleaved.
call2() {
  packs
  tar xzf build-pack-hc/bin/tests.tgz -C build-pack-hc/bin
  gpu_tests hc 'Cuda*:Sph*:Fluid*:Memory*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for n in 2 4; do
    for w in sd hc; do run D${n}_${w}_r1 dambreak-weak $n $w - --keep; done
    echo "cmp $n-GPU fluid.csv sd vs hc: $(cmp $R/D${n}_sd_r1/runs/*/fluid.csv $R/D${n}_hc_r1/runs/*/fluid.csv && echo identical)"
  done
  for r in 1 2 3; do
    for w in sd hc; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      [ $r -gt 1 ] && run D2_${w}_r$r dambreak-weak 2 $w -
      [ $r -gt 1 ] && run D4_${w}_r$r dambreak-weak 4 $w -
    done
  done
  for r in 1 2; do
    for w in sd hc; do
      run T2_${w}_r$r topple-weak 2 $w -
      run T4_${w}_r$r topple-weak 4 $w -
    done
  done
  for w in sd hc; do run T1_${w}_r1 topple-weak 1 $w 0; done
}

# Call 3 (2 x H200): so's tests; the two-GPU fluid.csv of sd and so compared; five interleaved
# rounds of the dam break at one and two GPUs.
call3() {
  packs
  tar xzf build-pack-so/bin/tests.tgz -C build-pack-so/bin
  gpu_tests so 'Cuda*:Sph*:Fluid*:Memory*:RadixSort*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for w in sd so; do run D2_${w}_r1 dambreak-weak 2 $w - --keep; done
  echo "cmp 2-GPU fluid.csv sd vs so: $(cmp $R/D2_sd_r1/runs/*/fluid.csv $R/D2_so_r1/runs/*/fluid.csv && echo identical)"
  for w in sd so; do run D1_${w}_r1 dambreak-weak 1 $w 0; done
  d12_rounds 2 5 sd so
}

# Call 4 (4 x H200): the dam break at one, two and four GPUs, sd and so interleaved; the cube
# block at four GPUs (its halo's device buffers and bounced uploads changed too).
call4() {
  packs
  for r in 1 2 3; do
    for w in sd so; do
      run D1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG))
      run D2_${w}_r$r dambreak-weak 2 $w -
      run D4_${w}_r$r dambreak-weak 4 $w -
    done
  done
  for r in 1 2; do
    for w in sd so; do run C4_${w}_r$r cubes-weak 4 $w -; done
  done
}

"$1"
finish_call
