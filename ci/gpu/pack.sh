#!/usr/bin/env bash
# Builds the CUDA configuration here (a machine with nvcc, no GPU needed) and packs what a
# GPU machine needs into PACK (default build-cuda-pack): bin/ (qdemsph, qdemsph_tests,
# qdemsph_bench), lib/ (shared libraries the GPU machines lack) and, in the repository's
# layout, the scripts and scenes the session uses (ci/, the verification scenes it runs,
# scaling/sph_bench.py), so the pack runs on its own even where the checkout is another
# branch. Carry PACK to the GPU machine and run PACK/ci/gpu_session.sh OUTDIR there; it sets
# LD_LIBRARY_PATH=PACK/lib. Uses ccache when present.
# PACK_MPI=1 (opt-in, for scaling/gpu_sweep.sh): build with MPI (QDEMSPH_MPI=ON) into
# build-cuda-mpi and pack build-cuda-mpi-pack (+ REVISION, + qdemsph_mpi_tests, whose
# device-resident halo test needs GPUs: mpirun -np 2 bin/qdemsph_mpi_tests); the GPU machines have Open MPI
# 4.1.6 (libmpi.so.40), so libmpi is not packed.
#
# gmsh: the GPU machines have none, and libgmsh pulls in ~300 MB (OpenCASCADE, FLTK, ...).
# lib/ gets a stub libgmsh.so.4.8 exporting the same gmsh:: functions, each throwing
# "gmsh is not available"; only .msh import and shogi meshing need it, which the GPU session
# does not use (box meshes only).
set -euo pipefail
MPI=OFF SUFFIX=
if [ "${PACK_MPI:-0}" = 1 ]; then MPI=ON SUFFIX=-mpi; fi
BUILD=${BUILD:-build-cuda$SUFFIX}
PACK=${1:-build-cuda$SUFFIX-pack}
JOBS=${JOBS:-2}
cd "$(dirname "$0")/../.."
LAUNCH=()
if command -v ccache >/dev/null; then
  LAUNCH=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B "$BUILD" -DQDEMSPH_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 -DQDEMSPH_MPI=$MPI \
  -DCMAKE_BUILD_TYPE=Release "${LAUNCH[@]}" >/dev/null
BINS=(qdemsph qdemsph_tests qdemsph_bench)
if [ $MPI = ON ]; then BINS+=(qdemsph_mpi_tests); fi  # the device-resident halo's test
cmake --build "$BUILD" -j "$JOBS" --target "${BINS[@]}"
rm -rf "$PACK"
mkdir -p "$PACK/bin" "$PACK/lib"
for b in "${BINS[@]}"; do cp "$BUILD/bin/$b" "$PACK/bin/"; done
strip "$PACK"/bin/* || true
if [ $MPI = ON ]; then git rev-parse --short HEAD >"$PACK/REVISION" 2>/dev/null || true; fi

# Stub gmsh: every exported gmsh:: C++ API function jumps to one function that throws.
GMSH=$(ldd "$PACK/bin/qdemsph" | awk '/libgmsh/ {print $3}')
if [ -n "$GMSH" ]; then
  STUB=$(mktemp -d)
  {
    echo '#include <stdexcept>'
    echo 'extern "C" [[noreturn]] void qdemsph_gmsh_missing() {'
    echo '  throw std::runtime_error("gmsh is not available on this machine (stub libgmsh from ci/gpu/pack.sh)");'
    echo '}'
    echo '__asm__('
    nm -D --defined-only "$GMSH" | awk '$2 == "T" && $3 ~ /^_ZN4gmsh/ {print $3}' | sort -u |
      while read -r s; do
        printf '  ".globl %s\\n.type %s,@function\\n%s: jmp qdemsph_gmsh_missing@PLT\\n"\n' "$s" "$s" "$s"
      done
    echo ');'
  } >"$STUB/gmsh_stub.cpp"
  g++ -shared -fPIC -O1 -Wl,-soname,"$(basename "$GMSH")" -o "$PACK/lib/$(basename "$GMSH")" "$STUB/gmsh_stub.cpp"
  rm -rf "$STUB"
fi
# Libraries the GPU machines (Ubuntu 24.04 + CUDA 13) lack or have in another version.
for b in "$PACK"/bin/*; do
  ldd "$b" | awk '/=> \// {print $3}'
done | sort -u | while read -r lib; do
  case "$(basename "$lib")" in
    libyaml-cpp.so.0.7*|libfmt.so.9*|libcudart.so.13*|libhdf5_serial.so.103*|libsz.so.2*|libaec.so.0*)
      cp -L "$lib" "$PACK/lib/" ;;
  esac
done
# The scripts and scenes ci/gpu_session.sh uses, at their repository paths.
for f in ci/gpu_session.sh ci/gpu scaling/sph_bench.py solver/tests/data solver/fuzz/crashes \
  verification/cases/contact_stack verification/cases/contact_impact \
  verification/cases/contact_sliding verification/cases/sph_dam_break \
  verification/cases/cantilever_exact/scene_box.yaml; do
  mkdir -p "$PACK/$(dirname "$f")"
  cp -r "$f" "$PACK/$(dirname "$f")/"
done
# The unit tests look for their data where this checkout has it (QDEMSPH_TEST_DATA).
echo "$PWD/solver/tests/data" >"$PACK/test_data_dir"
du -sh "$PACK"
ls -la "$PACK/bin" "$PACK/lib"
