#!/bin/bash
# The device calls of this folder (README.md), as they ran: `bash calls.sh callN` in the
# repository root of a device machine, with the packs of README's table carried as
# build-pack-<pack> (helpers: scaling/device_calls.sh; the calls were written with them after
# they ran: the same runs in the same order).
. scaling/device_calls.sh

# The packs: ce1dc5e (sd, the fluid layout before); 62af779 (lg: the layout's fields gathered
# on the device, the halo's device buffers mapped again only where they grow); 8d56b03 (hc: lg
# with the bounced copies' host side on the threads); 0009c56 (so: hc with the key-order sort
# on the device); b4c1048 (fin: the session's last code, one take_owned for all fields and
# for_each_coarse). Calls 2-4 and 6 carried the test binaries as bin/tests.tgz (the carry's
# size).
packs() {
  wrapper sd sd ce1dc5e
  wrapper lg lg 62af779
  wrapper hc hc 8d56b03
  wrapper so so 0009c56
  wrapper fin fin b4c1048
  wrapper rv rv 61dd27c
}

# Call 1 (4 x H200): lg's distributed GPU tests (the pack carried without qdemsph_tests: the
# carry's size); the two- and four-GPU fluid.csv of sd and lg compared; the dam break at one,
# two and four GPUs, sd and lg interleaved.
call1() {
  packs
  (cd build-pack-lg && LD_LIBRARY_PATH=$PWD/lib mpirun --allow-run-as-root -np 2 ./bin/qdemsph_mpi_tests \
    --gtest_filter='DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*' >$R/gputests_mpi.log 2>&1)
  echo "mpi tests rc=$? $(grep -aE 'PASSED|FAILED' $R/gputests_mpi.log | tail -2 | tr '\n' ' ')"
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  same_fluid 2 sd lg
  same_fluid 4 sd lg
  d_rounds 1 1 "1" sd lg
  d_rounds 2 3 "1 2 4" sd lg
  d_rounds 4 4 "2 4" sd lg
}

# tests PACK FILTER: PACK's tests (FILTER: the one-GPU ones), its binaries carried as
# bin/tests.tgz.
tests() {
  tar xzf build-pack-$1/bin/tests.tgz -C build-pack-$1/bin
  gpu_tests $1 "$2" 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
}

# Call 2 (4 x H200): hc's tests; as call 1 for hc, without the fourth round; the dominoes at two
# and four GPUs, two rounds, and at one.
call2() {
  packs
  tests hc 'Cuda*:Sph*:Fluid*:Memory*'
  same_fluid 2 sd hc
  same_fluid 4 sd hc
  d_rounds 1 1 "1" sd hc
  d_rounds 2 3 "1 2 4" sd hc
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
  tests so 'Cuda*:Sph*:Fluid*:Memory*:RadixSort*'
  same_fluid 2 sd so
  d_rounds 1 1 "1" sd so
  d12_rounds 2 5 sd so
}

# Call 4 (4 x H200): the dam break at one, two and four GPUs, sd and so interleaved; the cube
# block at four GPUs (its halo's device buffers and bounced uploads changed too).
call4() {
  packs
  d_rounds 1 3 "1 2 4" sd so
  for r in 1 2; do
    for w in sd so; do run C4_${w}_r$r cubes-weak 4 $w -; done
  done
}

# Call 5 (2 x H200): the dam break's 3000-step runs (0.14 s: the surge under way, layouts more
# often), sd and so interleaved, two rounds.
call5() {
  packs
  for r in 1 2; do
    for w in sd so; do
      run L1_${w}_r$r dambreak-weak 1 $w $(((r - 1) % NG)) --param steps=3000
      run L2_${w}_r$r dambreak-weak 2 $w - --param steps=3000
    done
  done
}

# Call 6 (2 x H200, fin carried alone: the carry's size): fin's tests; a round of the dam break
# at one and two GPUs.
call6() {
  packs
  tests fin 'Cuda*:Sph*:Fluid*:Memory*:RadixSort*:HostSelect*'
  d12_rounds 1 1 fin
}

# Call 7 (2 x H200, rv carried alone): as call 6 for rv (61dd27c: the review's up_room).
call7() {
  packs
  tests rv 'Cuda*:Sph*:Fluid*:Memory*:RadixSort*:HostSelect*'
  d12_rounds 1 1 rv
}

"$1"
finish_call
