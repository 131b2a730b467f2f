// qdemsph_bench: throughput of the element + integration step (one velocity-Verlet step:
// kick, drift, element forces + gather, kick) on elastic cube blocks, on the CPU or CUDA
// backend, with the memory traffic counted from the data layout.
//
//   qdemsph_bench --backend cuda --tets 1e6,1e7 --largest --json OUT.json
//   qdemsph_bench --backend cpu  --tets 1e6,1e7 --json OUT.json   (all OpenMP threads)
//
// Blocks: n^3 hexes, 12 tets each (n = round(cbrt(N / 12))), SVK elastic, the x = 0 face
// fixed, a small shear pre-deformation so every stress is non-zero; dt = 0.5 x the limit.
// The model is assembled here directly (no surface analysis, no loads) so that sizes near
// the GPU's capacity stay cheap on the host.
//
// Bytes per step (compulsory traffic: every array element read or written once per kernel,
// vertices gathered by the element kernel counted once; nv vertices, nt tets, 4 nt corners):
//   kick (x2)      f 24 + 1/m 8 + v 24 read + v 24 write        = 80 B/vertex, twice
//   drift          v 24 + x 24 read + x 24 write                = 72 B/vertex
//   element        corners tv 16, dX^-1 72, V0 8, material 4, corner forces 96 written,
//                  dissipation 8 read + 8 written               = 212 B/tet
//                  x 24 + v 24 of each vertex                   = 48 B/vertex
//   gather         CSR offset 8, f_ext 24, m 8, f 24 written    = 64 B/vertex
//                  CSR entries 4 x 8, corner forces 96 read     = 128 B/tet
//   total          340 B/tet + 344 B/vertex per step (~397 B/tet for nv ~ nt/6.5)
// Mass damping is off (alpha = 0): with it the gather also reads v (24 B/vertex).
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "core/gpu_info.hpp"
#include "core/memory.hpp"
#include "integrate/backend.hpp"
#include "io/json.hpp"
#include "mesh/box.hpp"
#include "model/model.hpp"
#include "physics/element.hpp"

using namespace qdemsph;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

Model block_model(int n) {
  TetMesh mesh = make_box({0, 0, 0}, {1, 1, 1}, {n, n, n});
  Model m;
  m.materials.push_back(make_material(1, 1.0e7, 0.3, 1000.0, 0.0));
  const std::int64_t nt = static_cast<std::int64_t>(mesh.tets.size());
  const std::int64_t nv = static_cast<std::int64_t>(mesh.points.size());
  m.X = std::move(mesh.points);
  m.tets = std::move(mesh.tets);
  m.dX_inv.resize(nt);
  m.vol0.resize(nt);
  m.tet_material.assign(nt, 0);
#pragma omp parallel for schedule(static)
  for (std::int64_t t = 0; t < nt; ++t) {
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = m.X[m.tets[t][k]];
    const Mat3 dX = edge_matrix(p);
    m.dX_inv[t] = inverse(dX);
    m.vol0[t] = det(dX) / 6.0;
  }
  m.mass.assign(nv, 0.0);
  for (std::int64_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) m.mass[m.tets[t][k]] += m.materials[0].density * m.vol0[t] / 4.0;
  m.inv_mass.resize(nv);
  m.x.resize(nv);
  m.v.assign(nv, Vec3{});
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < nv; ++i) {
    const Vec3 X = m.X[i];
    const bool fixed = X.x == 0.0;
    m.inv_mass[i] = fixed ? 0.0 : 1.0 / m.mass[i];
    m.x[i] = fixed ? X : X + Vec3{0.0, 0.0, 0.01 * X.x * X.x};
  }
  m.relax_inv_mass = m.inv_mass;
  m.fext.assign(nv, Vec3{});
  m.fpre.assign(nv, Vec3{});
  m.n_free_vertices = nv;
  m.n_free_tets = nt;
  // Uniform mesh: every hex has the same 12 tets, so the first hex sets the limit.
  m.dt_critical = 1e300;
  for (std::int64_t t = 0; t < std::min<std::int64_t>(12, nt); ++t) {
    Vec3 p[4];
    for (int k = 0; k < 4; ++k) p[k] = m.X[m.tets[t][k]];
    m.dt_critical = std::min(m.dt_critical, tet_critical_dt(m.materials[0], min_altitude(p)));
  }
  m.dt_critical_tet = 0;
  BodyRange b;
  b.name = "block";
  b.v_end = nv;
  b.t_end = nt;
  m.bodies.push_back(b);
  return m;
}

double layout_bytes_per_step(std::int64_t nt, std::int64_t nv) { return 340.0 * nt + 344.0 * nv; }

// Host copy bandwidth (bytes read + written per second), all threads, best of reps.
double host_copy_bandwidth(std::size_t bytes, int reps) {
  const std::size_t n = bytes / sizeof(double);
  std::vector<double> a(n), b(n);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) a[i] = 1.0, b[i] = 0.0;
  double best = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
#pragma omp parallel
    {
      const std::size_t nth = omp_get_num_threads(), id = omp_get_thread_num();
      const std::size_t lo = n * id / nth, hi = n * (id + 1) / nth;
      std::memcpy(b.data() + lo, a.data() + lo, (hi - lo) * sizeof(double));
    }
    best = std::min(best, seconds_since(t0));
    std::swap(a, b);
  }
  return 2.0 * n * sizeof(double) / best;
}

struct Args {
  std::string backend = "cuda";
  std::vector<double> tets = {1e6, 1e7};
  bool largest = false;
  double largest_fill = 0.9;  // fraction of free GPU memory the largest block may use
  double min_seconds = 1.0;   // timed work per size
  std::string json;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("missing value after " + s);
      return argv[++i];
    };
    if (s == "--backend")
      a.backend = next();
    else if (s == "--tets") {
      a.tets.clear();
      std::string v = next();
      for (std::size_t p = 0; p < v.size();) {
        const std::size_t q = v.find(',', p);
        a.tets.push_back(std::stod(v.substr(p, q - p)));
        p = q == std::string::npos ? v.size() : q + 1;
      }
    } else if (s == "--largest")
      a.largest = true;
    else if (s == "--largest-fill")
      a.largest_fill = std::stod(next());
    else if (s == "--seconds")
      a.min_seconds = std::stod(next());
    else if (s == "--json")
      a.json = next();
    else
      throw std::runtime_error("unknown argument " + s +
                               " (use --backend cpu|cuda --tets N,N --largest --json FILE)");
  }
  return a;
}

Json run_size(const Args& a, int n, double copy_bw, const std::string& label) {
  Json r = Json::object();
  const auto tb = Clock::now();
  Model m = block_model(n);
  const double build_s = seconds_since(tb);
  const std::int64_t nt = m.n_tets(), nv = m.n_vertices();
  const GpuInfo g0 = gpu_info();
  auto be = make_backend(a.backend);
  const auto tu = Clock::now();
  be->upload(m);
  be->sync();
  const double upload_s = seconds_since(tu);
  const GpuInfo g1 = gpu_info();
  const double dt = 0.5 * m.dt_critical;
  m = Model{};  // the host copy is no longer needed
  auto step = [&] {
    be->kick(0.5 * dt);
    be->drift(dt);
    be->compute_forces(dt, 0.0);
    be->kick(0.5 * dt);
  };
  be->compute_forces(0.0, 0.0);
  for (int s = 0; s < 3; ++s) step();
  be->sync();
  // Steps for about min_seconds of timed work.
  auto t0 = Clock::now();
  for (int s = 0; s < 3; ++s) step();
  be->sync();
  const double est = seconds_since(t0) / 3;
  const int steps = static_cast<int>(std::clamp(a.min_seconds / std::max(est, 1e-9), 5.0, 5000.0));
  t0 = Clock::now();
  for (int s = 0; s < steps; ++s) step();
  be->sync();
  const double step_s = seconds_since(t0) / steps;
  // Per-phase split, synchronising after each phase.
  double t_el = 0, t_int = 0;
  const int split = std::max(3, steps / 4);
  for (int s = 0; s < split; ++s) {
    auto t = Clock::now();
    be->kick(0.5 * dt);
    be->drift(dt);
    be->sync();
    t_int += seconds_since(t);
    t = Clock::now();
    be->compute_forces(dt, 0.0);
    be->sync();
    t_el += seconds_since(t);
    t = Clock::now();
    be->kick(0.5 * dt);
    be->sync();
    t_int += seconds_since(t);
  }
  const std::int64_t bad_tet = be->take_inverted_tet();
  const std::int64_t bad_v = be->find_non_finite();
  const double bytes = layout_bytes_per_step(nt, nv);
  const double bw = bytes / step_s;
  r["label"] = label;
  r["backend"] = be->name();
  r["threads"] = a.backend == "cpu" ? omp_get_max_threads() : 0;
  r["cells_per_axis"] = n;
  r["n_tets"] = nt;
  r["n_vertices"] = nv;
  r["steps_timed"] = steps;
  r["step_s"] = step_s;
  r["tet_updates_per_s"] = nt / step_s;
  r["elements_s_per_step"] = t_el / split;
  r["integration_s_per_step"] = t_int / split;
  r["bytes_per_step_layout"] = bytes;
  r["bytes_per_tet_step"] = bytes / nt;
  r["achieved_bandwidth_Bps"] = bw;
  r["copy_bandwidth_Bps"] = copy_bw;
  r["bandwidth_fraction"] = copy_bw > 0 ? bw / copy_bw : 0.0;
  r["state_bytes"] = be->device_bytes();
  r["state_bytes_per_tet"] = static_cast<double>(be->device_bytes()) / nt;
  if (a.backend == "cuda") {
    const double used = static_cast<double>(g0.free_bytes) - static_cast<double>(g1.free_bytes);
    r["gpu_bytes_used"] = used;
    r["gpu_bytes_per_tet"] = used / nt;
    r["gpu_total_bytes"] = g1.total_bytes;
  }
  r["host_build_s"] = build_s;
  r["upload_s"] = upload_s;
  r["healthy"] = bad_tet < 0 && bad_v < 0;
  fmt::print(
      "{:<8} {:<5} {:>12} tets  {:>9.3e} tet-updates/s  step {:>9.3f} ms  "
      "{:>5.0f} B/tet-step  {:>7.1f} GB/s = {:>5.1f} % of copy  {:>5.0f} B/tet state{}\n",
      label, be->name(), nt, nt / step_s, 1e3 * step_s, bytes / nt, bw * 1e-9,
      copy_bw > 0 ? 100 * bw / copy_bw : 0.0, static_cast<double>(be->device_bytes()) / nt,
      bad_tet < 0 && bad_v < 0 ? "" : "  UNHEALTHY");
  std::fflush(stdout);
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    Json rec = Json::object();
    rec["program"] = "qdemsph_bench";
    rec["backend"] = a.backend;
    const GpuInfo g = gpu_info();
    Json gj = Json::object();
    gj["available"] = g.available;
    gj["summary"] = gpu_summary(g);
    gj["name"] = g.name;
    gj["sm_count"] = g.sm_count;
    gj["compute_capability"] = fmt::format("{}.{}", g.cc_major, g.cc_minor);
    gj["total_bytes"] = g.total_bytes;
    gj["runtime_version"] = g.runtime_version;
    gj["driver_version"] = g.driver_version;
    rec["gpu"] = gj;
    rec["host_threads"] = omp_get_max_threads();
    double copy_bw = 0;
    if (a.backend == "cuda") {
      copy_bw = gpu_copy_bandwidth(std::size_t{2} << 30, 10);
      rec["copy_bandwidth_method"] =
          "cudaMemcpy device-to-device of 2 GiB, best of 10, read+write bytes";
    } else {
      copy_bw = host_copy_bandwidth(std::size_t{1} << 30, 10);
      rec["copy_bandwidth_method"] =
          "OpenMP-parallel memcpy of 1 GiB, best of 10, read+write bytes";
    }
    rec["copy_bandwidth_Bps"] = copy_bw;
    fmt::print("backend {}; {}; copy bandwidth {:.1f} GB/s; {} host threads\n", a.backend,
               gpu_summary(g), copy_bw * 1e-9, omp_get_max_threads());
    Json runs = Json::array();
    double bytes_per_tet = 0;
    for (double want : a.tets) {
      const int n = std::max(1, static_cast<int>(std::lround(std::cbrt(want / 12.0))));
      Json r = run_size(a, n, copy_bw, fmt::format("{:.0e}", want));
      runs.push_back(r);
      rec["runs"] = runs;
      if (!a.json.empty()) rec.write_file(a.json);  // kept if a later size fails
    }
    rec["runs"] = runs;
    if (a.largest && a.backend == "cuda") {
      // Size from the layout: state bytes per tet of a block measured on a small one.
      auto probe = make_backend(a.backend);
      const Model pm = block_model(20);
      probe->upload(pm);
      bytes_per_tet = static_cast<double>(probe->device_bytes()) / pm.n_tets();
      probe.reset();
      const GpuInfo gf = gpu_info();
      const double fit = a.largest_fill * gf.free_bytes / bytes_per_tet;
      const int n = static_cast<int>(std::floor(std::cbrt(fit / 12.0)));
      Json l = Json::object();
      l["free_bytes_before"] = gf.free_bytes;
      l["state_bytes_per_tet"] = bytes_per_tet;
      l["fill_fraction"] = a.largest_fill;
      l["max_tets_by_memory"] = gf.free_bytes / bytes_per_tet;
      l["max_tets_by_int32_indices"] = 2147483647.0;
      rec["largest_sizing"] = l;
      fmt::print("largest: {:.3g} tets fit in {:.1f} GiB free at {:.0f} B/tet; running n = {}\n",
                 gf.free_bytes / bytes_per_tet, gf.free_bytes / 1073741824.0, bytes_per_tet, n);
      std::fflush(stdout);
      rec["largest"] = run_size(a, n, copy_bw, "largest");
    }
    if (!a.json.empty()) rec.write_file(a.json);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "qdemsph_bench: {}\n", e.what());
    return 1;
  }
}
