#!/bin/bash
# The six device calls of this folder (README.md), as they ran: `bash calls.sh callN` in the
# repository root of a device machine, with the packs of README's table carried as
# build-pack-<pack> (helpers: scaling/device_calls.sh).
. scaling/device_calls.sh

# Call 1: both hooks at 256, 128 and 64 threads a block; fluid.csv of the one-GPU runs compared.
call1() {
  for b in 256 128 64; do wrapper b$b blk d94fa87+exp-block-$b QDEMSPH_EXP_BLOCK3=$b QDEMSPH_EXP_BLOCK2=$b; done
  for r in 1 2 3; do
    for b in 256 128 64; do
      run D1_b${b}_r$r dambreak-weak 1 b$b $(((r - 1) % NG)) --keep
      run D2_b${b}_r$r dambreak-weak 2 b$b -
    done
  done
  for b in 128 64; do
    echo "cmp 256 vs $b: $(cmp $R/D1_b256_r1/runs/*/fluid.csv $R/D1_b${b}_r1/runs/*/fluid.csv && echo identical)"
  done
  for r in 1 2; do
    for b in 256 128; do
      run T1_b${b}_r$r topple-weak 1 b$b $(((r - 1) % NG))
      run T2_b${b}_r$r topple-weak 2 b$b -
      run C1_b${b}_r$r cubes-weak 1 b$b $(((r - 1) % NG))
    done
  done
}

# Call 2: the tests of e4836c0 (b64); the SPH passes at 256 (base), 64 (b64) and 32 (x32); the
# contact kernel at 256, 128 and 64.
call2() {
  wrapper base blk d94fa87+exp-block-base QDEMSPH_EXP_BLOCK3=256 QDEMSPH_EXP_BLOCK2=256
  wrapper b64 b64 e4836c0
  wrapper x32 blk d94fa87+exp-block-x32 QDEMSPH_EXP_BLOCK3=32 QDEMSPH_EXP_BLOCK2=256
  wrapper c128 blk d94fa87+exp-block-c128 QDEMSPH_EXP_BLOCK3=256 QDEMSPH_EXP_BLOCK2=128
  wrapper c64 blk d94fa87+exp-block-c64 QDEMSPH_EXP_BLOCK3=256 QDEMSPH_EXP_BLOCK2=64
  gpu_tests b64 'Cuda*:Sph*:Fluid*:Contact*:Memory*:LocalModel*'
  d12_rounds 1 4 base b64 x32
  for r in 1 2 3; do
    for w in base c128 c64; do run C1_${w}_r$r cubes-weak 1 $w $(((r - 1) % NG)); done
  done
  for r in 1 2; do
    for w in base c128 c64; do
      run T1_${w}_r$r topple-weak 1 $w $(((r - 1) % NG))
      run T2_${w}_r$r topple-weak 2 $w -
    done
  done
}

# Calls 3-5: 92d07b5 (c64) against d94fa87 (the blk pack, its hook unset).
finals() {
  wrapper base blk d94fa87+exp-block-inert
  wrapper c64 c64 92d07b5
}

# Call 3 (2 x H200): the tests of 92d07b5; the cube block's and the dominoes' energies and contact
# counts with both packs; interleaved rounds of the three cases at one and two GPUs.
call3() {
  finals
  gpu_tests c64 'Cuda*:Contact*:LocalModel*:Sph*'
  for s in C:cubes-weak T:topple-weak; do
    k=${s%%:*} sw=${s#*:}
    for w in base c64; do run ${k}1_${w}_r1 $sw 1 $w 0 --keep; done
    python3 -c "
import json, glob
a, b = [json.load(open(glob.glob('$R/${k}1_' + w + '_r1/runs/*/summary.json')[0])) for w in ('base', 'c64')]
same = (a['contact'], a['energies']) == (b['contact'], b['energies'])
print('$k summary energies+contact', 'identical' if same else 'DIFFER', a['energies'], b['energies'])"
    for w in base c64; do run ${k}2_${w}_r1 $sw 2 $w -; done
  done
  for r in 2 3; do
    for s in C:cubes-weak T:topple-weak; do
      k=${s%%:*} sw=${s#*:}
      for w in base c64; do
        run ${k}1_${w}_r$r $sw 1 $w $(((r - 1) % NG))
        run ${k}2_${w}_r$r $sw 2 $w -
      done
    done
  done
  d12_rounds 1 2 base c64
}

# Call 4 (4 x H200): the three cases at 1, 2 and 4 GPUs, two rounds.
call4() {
  finals
  for r in 1 2; do
    for s in D:dambreak-weak C:cubes-weak T:topple-weak; do
      k=${s%%:*} sw=${s#*:}
      for w in base c64; do
        if [ $w = base ]; then g=$(((2 * r - 2) % NG)); else g=$(((2 * r - 1) % NG)); fi
        run ${k}1_${w}_r$r $sw 1 $w $g
        run ${k}2_${w}_r$r $sw 2 $w -
        run ${k}4_${w}_r$r $sw 4 $w -
      done
    done
  done
}

# Call 5 (another 4 x H200 host): the dam break and the dominoes at four GPUs, c64 first.
call5() {
  finals
  for r in 1 2 3; do
    for w in c64 base; do run D4_${w}_r$r dambreak-weak 4 $w -; done
    for w in c64 base; do run T4_${w}_r$r topple-weak 4 $w -; done
  done
}

# Call 6 (2 x H200), rejected: the dam break at two GPUs with the fluid's first skin half a kernel
# support (s50: 41a55bb with kFluidSkin = 0.5) against 92d07b5.
call6() {
  wrapper c64 c64 92d07b5
  wrapper s50 s50 41a55bb+fluid-skin-0.5
  run D2_s50_r1 dambreak-weak 2 s50 -
  run D2_c64_r1 dambreak-weak 2 c64 -
  run D2_s50_r2 dambreak-weak 2 s50 -
  run D2_c64_r2 dambreak-weak 2 c64 -
  run D1_s50_r1 dambreak-weak 1 s50 0
  run D2_s50_r3 dambreak-weak 2 s50 -
  run D2_c64_r3 dambreak-weak 2 c64 -
}

"$1"
finish_call
