#!/bin/bash
# The device calls of this folder (README.md), as they ran: `bash calls.sh callN` in the
# repository root of a device machine, with the packs of README's table carried as
# build-pack-<pack> (helpers: scaling/device_calls.sh).
. scaling/device_calls.sh

# The packs: 92d07b5 (c64, the SPH code before); 86eb7d3 (ov: the passes over particles no
# ghost is near run while the pressure refreshes travel, split by a test per particle;
# rejected); 6e657c4 (ol: split by lists made at the sort; rejected, reverted by 14de646);
# f45f64d (tr: the refreshes without the waits for the timers; no gain, reverted by e67e020);
# ce1dc5e (sd: ol with the passes near ghosts on the side stream; landed). The rejected packs'
# records were relabelled "+split-rejected" and "+waits-rejected" after the calls (README).
# Call 4 carried build-pack-fin (e67e020) for its tests only.
packs() {
  wrapper c64 c64 92d07b5
  wrapper ov ov 86eb7d3
  wrapper ol ol 6e657c4
  wrapper tr tr f45f64d
  wrapper sd sd ce1dc5e
}

# rounds PACK ORDER LAST: PACK's tests; the two-GPU fluid.csv of c64 and PACK compared (round
# 1); interleaved rounds 2..LAST of the dam break at one and two GPUs, the packs in ORDER.
rounds() {
  local x=$1 order=$2 last=$3
  gpu_tests $x 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  for w in c64 $x; do run D2_${w}_r1 dambreak-weak 2 $w - --keep; done
  echo "cmp two-GPU fluid.csv c64 vs $x: $(cmp $R/D2_c64_r1/runs/*/fluid.csv $R/D2_${x}_r1/runs/*/fluid.csv && echo identical)"
  for w in c64 $x; do run D1_${w}_r1 dambreak-weak 1 $w 0; done
  d12_rounds 2 $last $order
}

# Call 1 (2 x H200): ov against c64, ov first in each round.
call1() {
  packs
  rounds ov "ov c64" 4
}

# Call 2 (2 x H200): ol against c64.
call2() {
  packs
  rounds ol "c64 ol" 4
}

# Call 3 (2 x H200): the tests of tr (f45f64d: the refreshes' waits trimmed, on the reverted
# split); interleaved rounds of the dam break at one and two GPUs, c64 and tr.
call3() {
  packs
  gpu_tests tr 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
  d12_rounds 1 5 c64 tr
}

# Call 4 (2 x H200): the tests of fin (e67e020: 92d07b5's solver and the new GPU test of the
# distributed fluid).
call4() {
  gpu_tests fin 'Cuda*:Sph*:Fluid*' 'DistributedFluid.*:Distributed.GpuRanks*:HaloPlan.*'
  grep -a "fluid dam break on GPUs" $R/gputests_mpi.log
}

# Call 5 (2 x H200): sd (ce1dc5e: the split with lists, the passes near ghosts on the side
# stream) against c64.
call5() {
  packs
  rounds sd "c64 sd" 5
}

# Call 6 (4 x H200): the dam break at one, two and four GPUs, c64 and sd interleaved.
call6() {
  packs
  d_rounds 1 3 "1 2 4" c64 sd
}

"$1"
finish_call
