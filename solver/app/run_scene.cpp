#include "app/run_scene.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "core/gpu_info.hpp"
#include "core/progress.hpp"
#include "integrate/backend.hpp"
#include "integrate/restart.hpp"
#include "integrate/stepper.hpp"
#include "io/checkpoint_h5.hpp"
#include "io/fields_h5.hpp"
#include "io/fluid_h5.hpp"
#include "io/json.hpp"
#include "io/probes_csv.hpp"
#include "mesh/gmsh_io.hpp"
#include "model/model.hpp"
#include "parallel/parallel_record.hpp"
#include "sph/fluid_stage.hpp"
#ifdef QDEMSPH_HAVE_MPI
#include "parallel/distributed_backend.hpp"
#include "parallel/fluid_exchange.hpp"
#include "parallel/world.hpp"
#endif

namespace qdemsph {
namespace {

// A probe resolved to vertex indices and weights: value = sum w_i * (x_i - X_i [disp]).
struct ResolvedProbe {
  std::vector<std::int64_t> vertices;
  std::vector<double> weights;
  bool displacement = true;
};

std::vector<ResolvedProbe> resolve_probes(const Scene& scene, const Model& model) {
  std::vector<ResolvedProbe> out;
  for (std::size_t p = 0; p < scene.probes.size(); ++p) {
    const ProbeSpec& ps = scene.probes[p];
    const BodyRange* body = nullptr;
    for (const auto& b : model.bodies)
      if (b.scene_index == ps.body) body = &b;
    ResolvedProbe r;
    r.displacement = ps.kind == ProbeSpec::Kind::Displacement;
    double wsum = 0;
    for (std::int64_t i = body->v_begin; i < body->v_end; ++i) {
      if (r.displacement && !ps.region.contains(model.X[i])) continue;
      const double w = r.displacement ? 1.0 : model.mass[i];
      r.vertices.push_back(i);
      r.weights.push_back(w);
      wsum += w;
    }
    if (r.vertices.empty())
      throw InputError(fmt::format("probes[{}] ('{}'): the region selects no vertex of body '{}'",
                                   p, ps.name, body->name));
    for (auto& w : r.weights) w /= wsum;
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<Vec3> evaluate_probes(const std::vector<ResolvedProbe>& probes, const Model& model,
                                  const std::vector<Vec3>& x) {
  std::vector<Vec3> vals;
  for (const auto& p : probes) {
    Vec3 s{0, 0, 0};
    for (std::size_t k = 0; k < p.vertices.size(); ++k) {
      const std::int64_t i = p.vertices[k];
      s += p.weights[k] * (p.displacement ? x[i] - model.X[i] : x[i]);
    }
    vals.push_back(s);
  }
  return vals;
}

Json energies_json(const Energies& e) {
  Json j = Json::object();
  j["kinetic"] = e.kinetic;
  j["strain"] = e.strain;
  j["potential"] = e.potential;
  j["dissipated"] = e.dissipated;
  j["contact"] = e.contact;
  j["contact_dissipated"] = e.contact_dissipated;
  j["total"] = e.total();
  return j;
}

Json relax_json(const RelaxResult& r) {
  Json j = Json::object();
  j["converged"] = r.converged;
  j["iterations"] = r.iterations;
  j["residual"] = r.residual;
  j["reference_force"] = r.reference;
  return j;
}

std::string stages_of(const Model& model, const FluidSetup* fluid) {
  std::string s = fmt::format("elements ({} free tets), integration ({} free vertices)",
                              model.n_free_tets, model.n_free_vertices);
  s += "; " + describe_contact(model);
  s += fluid ? "; " + describe_fluid(*fluid) : "; no SPH: no fluid";
  return s;
}

// The fluid's stable dt at the start: CFL with c0 and the free-fall speed sqrt(2 g H), the
// force limit with g, the viscous limit (sph_timestep.hpp).
double fluid_dt(const FluidSetup& f) {
  const double g = norm(f.params.gravity);
  return sph_dt_limits(f.params.kernel.h, f.params.eos.c0, std::sqrt(2.0 * g * f.height), g,
                       f.params.nu)
      .min();
}

// Under mpirun a file written by rank 0 alone must not fail on rank 0 alone (the others
// would wait forever): report and end every rank. On one rank, the error propagates.
template <class F>
void on_root(bool distributed, F&& write) {
#ifdef QDEMSPH_HAVE_MPI
  if (distributed) {
    try {
      write();
    } catch (const std::exception& e) {
      fmt::print(stderr, "qdemsph: error: {}\n", e.what());
      world_abort(2);
    }
    return;
  }
#endif
  (void)distributed;
  write();
}

// Distributed: every rank waits for the others here (after rank 0's file writes).
void wait_all_ranks(bool distributed) {
#ifdef QDEMSPH_HAVE_MPI
  if (distributed) world_barrier();
#endif
  (void)distributed;
}

// The fluid step H and the solid sub-steps k (H = k x the solid's dt): a fixed run.dt is
// shared (k = 1); otherwise as many solid steps as fit in the fluid's limit (at most
// fluid.solid_substeps).
double fluid_step(const Model& model, const Scene& scene, double dt_solid, double dt_fluid,
                  int& substeps) {
  substeps = 1;
  if (scene.run.dt) return *scene.run.dt;
  if (model.dt_critical_tet < 0 || dt_solid >= dt_fluid) return dt_fluid;
  substeps = std::max(1, static_cast<int>(std::floor(dt_fluid / dt_solid)));
  if (scene.fluid.solid_substeps) substeps = std::min(substeps, *scene.fluid.solid_substeps);
  return substeps * dt_solid;
}

}  // namespace

int run_scene(const Scene& scene, const RunOptions& opt) {
  const auto wall0 = std::chrono::steady_clock::now();
  const std::string backend_name = opt.backend.value_or(scene.run.backend);
  if (scene.run.threads > 0)
    omp_set_num_threads(scene.run.threads);
  else if (!std::getenv("OMP_NUM_THREADS")) {
    int local_ranks = 1;
#ifdef QDEMSPH_HAVE_MPI
    local_ranks = world().local_size;
#endif
    omp_set_num_threads(default_host_threads(omp_get_num_procs(),
                                             static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN)),
                                             local_ranks, backend_name == "cuda"));
  }
  const Model model = build_model(scene);
  std::unique_ptr<Backend> be = make_backend(backend_name);
  // Under mpirun with several ranks, the backend is the distributed decorator around it
  // (docs/parallel.md); rank 0 writes every file.
  bool distributed = false, root = true;
#ifdef QDEMSPH_HAVE_MPI
  DistributedBackend* dist = nullptr;
  if (world().size > 1) {
    auto d = make_distributed_backend(std::move(be), parallel_options(scene.parallel));
    dist = d.get();
    be = std::move(d);
    distributed = true;
    root = world().root();
  }
#endif
  be->upload(model);
  double dt = choose_dt(model, scene.run.dt, scene.run.dt_safety);
  std::optional<FluidSetup> fluid_setup;
  std::unique_ptr<FluidStage> fluid;
#ifdef QDEMSPH_HAVE_MPI
  FluidExchange* fluid_exchange = nullptr;  // the stage's, asked for its traffic at the end
#endif
  int solid_substeps = 1;
  if (scene.fluid.present) {
    fluid_setup = build_fluid(scene.fluid, scene.gravity);
    if (scene.fluid.couple_bodies) add_solid_markers(*fluid_setup, model);
    const double dtf = fluid_dt(*fluid_setup);
    if (scene.run.dt && *scene.run.dt > dtf)
      throw InputError(
          fmt::format("run.dt = {:.4e} s exceeds the fluid's time-step limit {:.4e} s "
                      "(CFL with c0 = {:.4g} m/s)",
                      *scene.run.dt, dtf, fluid_setup->params.eos.c0));
    dt = fluid_step(model, scene, dt, dtf, solid_substeps);
    // Under mpirun the particles are distributed too (parallel/fluid_exchange.hpp).
    std::unique_ptr<FluidExchange> exchange;
#ifdef QDEMSPH_HAVE_MPI
    if (distributed)
      exchange = make_fluid_exchange(parallel_options(scene.parallel), *fluid_setup,
                                     backend_name == "cuda" ? Space::Cuda : Space::Host);
    fluid_exchange = exchange.get();
#endif
    SolidViews solid;
    if (fluid_setup->n_marker > 0) solid = be->solid_views();
    fluid = make_fluid_stage(backend_name, *fluid_setup, fluid_setup->n_marker ? &solid : nullptr,
                             std::move(exchange));
  }
  const std::filesystem::path dir = opt.out.value_or(scene.output.dir);
  const CheckpointSpec& cks = scene.output.checkpoint;
  const std::filesystem::path ckpt_dir = cks.dir.empty() ? dir / "checkpoints" : cks.dir;
  const FluidSetup* fsetup = fluid_setup ? &*fluid_setup : nullptr;
  // A restart is checked against the scene before any output is touched. Under mpirun every
  // rank reads the checkpoint; the backend's load_state gives each rank its share.
  std::optional<Checkpoint> restart;
  std::filesystem::path restart_path;
  if (opt.restart) {
    if (scene.run.mode == RunMode::Static)
      throw InputError("--restart: a static run (run.mode: static) has no checkpoints");
    if (*opt.restart == "latest") {
      restart = read_latest_checkpoint(ckpt_dir, restart_path);
    } else {
      restart_path = *opt.restart;
      restart = read_checkpoint(restart_path);
    }
    check_checkpoint(*restart, restart_path.string(), scene, model, dt, fsetup);
  }
  const CheckpointOutput resume = restart ? restart->output : CheckpointOutput{-1, -1, -1, -1};
  const auto probes = resolve_probes(scene, model);
  std::vector<std::string> names;
  for (const auto& p : scene.probes) names.push_back(p.name);

  std::optional<FieldWriter> fields;
  std::optional<ProbeWriter> probe_csv;
  std::string open_error;
  if (root) try {
      fields.emplace(dir, model.X, model.tets, model.body, resume.field_frames);
      probe_csv.emplace(dir, names, resume.probes_bytes);
    } catch (const InputError& e) {
      if (!distributed) throw;
      open_error = e.what();
    }
#ifdef QDEMSPH_HAVE_MPI
  if (distributed && !world_all(open_error.empty()))
    throw InputError(open_error.empty() ? "rank 0 could not create the output files" : open_error);
#endif
  Stepper st(model, *be, dt);
  PhaseTimers& timers = st.timers();
  std::optional<FluidWriter> fluid_out;
  std::FILE* fluid_csv = nullptr;
  if (fluid) st.attach_fluid(fluid.get(), solid_substeps);
  if (fluid && root)
    on_root(distributed, [&] {
      fluid_out.emplace(dir, resume.fluid_frames);
      const std::string header =
          "time,kinetic,px,py,pz,v_max,rho_dev,x_max,y_max,dt_limit,fbx,fby,fbz\n";
      if (resume.fluid_csv_bytes >= 0) {
        fluid_csv = reopen_for_append(dir / "fluid.csv", resume.fluid_csv_bytes, header);
      } else {
        fluid_csv = std::fopen((dir / "fluid.csv").c_str(), "w");
        if (!fluid_csv) throw InputError("cannot create '" + (dir / "fluid.csv").string() + "'");
        std::fputs(header.c_str(), fluid_csv);
      }
    });
  if (restart)
    restore_checkpoint(*restart, restart_path.string(), scene, model, dt, *be, fluid.get(), fsetup,
                       st);
  // Checkpoints are gathered from every rank (Backend::save_state) and written by rank 0.
  const bool checkpointing = cks.enabled && scene.run.mode == RunMode::Dynamic;
  std::optional<CheckpointSeries> checkpoints;
  if (checkpointing && root) on_root(distributed, [&] { checkpoints.emplace(ckpt_dir, cks.keep); });

  Json summary = Json::object();
  summary["scene"] = scene.file.string();
  summary["name"] = scene.name;
  summary["backend"] = be->name();
  summary["threads"] = omp_get_max_threads();  // on a GPU: the host's (layouts, launches)
  summary["mode"] = scene.run.mode == RunMode::Static ? "static" : "dynamic";
  summary["n_bodies"] = model.bodies.size();
  summary["bodies"] = Json::array();  // index -> name, as fields.h5's /mesh/body numbers them
  for (const BodyRange& b : model.bodies) {
    Json bj = Json::object();
    bj["name"] = b.name;
    bj["fixed"] = b.fixed;
    bj["n_vertices"] = b.v_end - b.v_begin;
    bj["n_tets"] = b.t_end - b.t_begin;
    summary["bodies"].push_back(bj);
  }
  summary["gravity"] = Json::array();
  for (double g : {scene.gravity.x, scene.gravity.y, scene.gravity.z})
    summary["gravity"].push_back(g);
  summary["n_vertices"] = model.n_vertices();
  summary["n_tets"] = model.n_tets();
  summary["n_free_tets"] = model.n_free_tets;
  summary["dt"] = dt;
  summary["dt_critical"] = model.dt_critical;
  summary["stages"] = stages_of(model, fluid_setup ? &*fluid_setup : nullptr);
  if (fluid) {
    const SphParams& P = fluid->params();
    Json fj = Json::object();
    fj["n_fluid"] = fluid->n_fluid();
    fj["n_wall"] = fluid->size() - fluid->n_fluid();
    fj["spacing"] = fluid_setup->dx;
    fj["h"] = P.kernel.h;
    fj["c0"] = P.eos.c0;
    fj["rho0"] = P.eos.rho0;
    fj["n_marker"] = fluid->n_marker();
    fj["dt_limit"] = fluid_dt(*fluid_setup);
    fj["solid_substeps"] = solid_substeps;
    fj["device_bytes"] = fluid->device_bytes();
    summary["fluid"] = fj;
  }
  summary["device_bytes"] = be->device_bytes();
  if (restart) {
    summary["restarted_from"]["file"] = restart_path.string();
    summary["restarted_from"]["step"] = restart->step;
    summary["restarted_from"]["time"] = restart->time;
  }

  // The step of the last field frame and probe row (the end of the run adds them once).
  std::int64_t last_field_step = restart ? resume.last_field_step : -1;
  std::int64_t last_probe_step = restart ? resume.last_probe_step : -1;
  // Distributed: the other ranks wait for rank 0's write inside the scope, so the time goes
  // to "output" on every rank, not to the next step's first exchange. Rank 0 frees its copy of
  // the whole model before that wait (1 M vertices with stress: ~11 ms on a GPU host, which the
  // other ranks had waited for in the first step's exchange).
  auto write_fields = [&](bool stress) {
    auto scope = timers.scope("output");
    last_field_step = st.steps();
    {
      const HostFields h = be->download(stress);
      if (root)
        on_root(distributed,
                [&] { fields->write(st.time(), st.steps(), h.x, h.v, h.stress, h.von_mises); });
    }
    if (fluid) {
      const FluidHost fh = fluid->download();  // distributed: every particle on rank 0
      if (root)
        on_root(distributed, [&] {
          fluid_out->write(st.time(), st.steps(), fh.x, fh.v, fh.p, fh.rho, fh.type, fh.gid);
        });
    }
    wait_all_ranks(distributed);
  };
  auto write_probes = [&] {
    auto scope = timers.scope("output");
    last_probe_step = st.steps();
    {
      const HostFields h = be->download(false);  // freed before the wait, as in write_fields
      const Energies e = be->energies();
      if (root)
        on_root(distributed,
                [&] { probe_csv->write(st.time(), evaluate_probes(probes, model, h.x), e); });
    }
    if (fluid) {
      const FluidStats fs = fluid->stats();
      const FluidHost fh = fluid->download();
      const double dt_limit = fluid->dt_limits().min();
      if (root) {
        double xm = -1e300, ym = -1e300;
        for (std::size_t i = 0; i < fh.x.size(); ++i)
          if (fh.type[i] == kSphFluid) xm = std::max(xm, fh.x[i].x), ym = std::max(ym, fh.x[i].y);
        fmt::print(
            fluid_csv,
            "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.9g},{:.9g},{:.6g},{:.9g},{:.9g},"
            "{:.9g}\n",
            st.time(), fs.kinetic, fs.momentum.x, fs.momentum.y, fs.momentum.z, fs.v_max,
            fs.rho_dev, xm, ym, dt_limit, fs.force_on_bodies.x, fs.force_on_bodies.y,
            fs.force_on_bodies.z);
        std::fflush(fluid_csv);
      }
    }
    wait_all_ranks(distributed);
  };
  auto finish = [&](const std::string& status, std::int64_t steps) {
    summary["status"] = status;
    summary["steps"] = steps;
    summary["sim_time"] = st.time();
    summary["energies"] = energies_json(be->energies());
    Json phases = Json::object();
    std::map<std::string, double> phase_map = timers.seconds();
    for (const auto& [k, v] : timers.seconds()) phases[k] = v;
    // Contact runs inside the force evaluation: report it as phase "contact" (and its
    // sub-phases contact.broad / contact.narrow / contact.force), taken out of "elements".
    double contact_s = 0;
    for (const auto& [k, v] : be->stage_seconds()) {
      phases[k] = v;
      if (k.rfind("contact.", 0) == 0) contact_s += v;
    }
    if (model.contact.enabled) {
      phases["contact"] = phase_map["contact"] = contact_s;
      if (timers.seconds().count("elements"))
        phases["elements"] = phase_map["elements"] = timers.seconds().at("elements") - contact_s;
      Json cj = Json::object();
      for (const auto& [k, v] : be->contact_stats()) cj[k] = v;
      cj["d_dem"] = model.contact.d_dem;
      cj["broad_phase"] = broad_phase_name(model.contact.mode);
      cj["primitives"] = static_cast<std::int64_t>(model.contact.prim_v.size());
      cj["surface_tets"] = model.contact.n_surface_tets;
      cj["surface_triangles"] = static_cast<std::int64_t>(model.contact.tri_v.size());
      summary["contact"] = cj;
    }
    // A distributed fluid's upkeep inside "sph" (the skin test and ghost refreshes, the layout
    // rebuilds, the first layout) as sub-phases sph.halo / sph.rebuild / sph.setup; "sph"
    // stays the whole fluid step.
    if (fluid)
      for (const auto& [k, v] : fluid->stage_seconds()) phases[k] = phase_map[k] = v;
    summary["phases"] = phases;
#ifdef QDEMSPH_HAVE_MPI
    if (dist) {
      ParallelRecord r = dist->record(phase_map);
      if (fluid_exchange) r.set_fluid(fluid_exchange->traffic());
      summary["parallel"] = r.to_json();
    }
#endif
    if (!distributed)
      summary["parallel"] =
          serial_parallel_record(model, scene.parallel.curve, phase_map).to_json();
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    summary["wall_s"] = wall;
    summary["steps_per_s"] = steps > 0 ? steps / wall : 0.0;
    if (fluid) {
      const auto it = timers.seconds().find("sph");
      const double sph_s = it == timers.seconds().end() ? 0.0 : it->second;
      summary["fluid"]["particle_steps_per_s"] =
          sph_s > 0 ? static_cast<double>(fluid->size()) * st.steps() / sph_s : 0.0;
      if (fluid_csv) std::fclose(fluid_csv), fluid_csv = nullptr;
    }
    if (root) on_root(distributed, [&] { summary.write_file(dir / "summary.json"); });
  };

  ProgressLine progress(root && !opt.quiet && isatty(STDERR_FILENO));
  int code = 0;
  try {
    bool preload = false;
    for (const auto& l : scene.loads) preload = preload || l.preload;
    auto relax_progress = [&](std::int64_t it, double res) {
      const double frac =
          res > 0 ? std::clamp(std::log(res) / std::log(scene.run.static_tolerance), 0.0, 1.0)
                  : 1.0;
      progress.update(frac, it, fmt::format("residual {:.2e}", res).c_str());
    };
    if (scene.run.mode == RunMode::Static) {
      write_probes();
      const RelaxResult r =
          st.relax(scene.run.static_tolerance, scene.run.static_max_steps, false, relax_progress);
      progress.finish();
      summary["static"] = relax_json(r);
      write_probes();
      write_fields(true);
      if (!r.converged) {
        if (root)
          fmt::print(stderr,
                     "qdemsph: static solve did not converge: residual {:.3e} > tolerance {:.3e} "
                     "after {} steps (run.static.max_steps)\n",
                     r.residual, scene.run.static_tolerance, r.iterations);
        code = 3;
      } else if (!opt.quiet && root) {
        fmt::print("static solve converged: residual {:.3e} after {} steps\n", r.residual,
                   r.iterations);
      }
      finish(r.converged ? "converged" : "not_converged", r.iterations);
      return code;
    }
    if (preload && !restart) {
      const RelaxResult r =
          st.relax(scene.run.static_tolerance, scene.run.static_max_steps, true, relax_progress);
      progress.finish();
      summary["preload"] = relax_json(r);
      if (fluid) fluid->compute();  // the markers follow the bodies to the preloaded state
      if (!r.converged)
        throw SimulationError(fmt::format(
            "initial static solve (preload) did not converge: residual {:.3e} after {} steps",
            r.residual, r.iterations));
    }
    const double end = scene.run.end_time;
    const double probe_dt = scene.output.probes_every;
    const double field_dt = scene.output.fields_every;
    double next_probe = probe_dt, next_field = field_dt;
    if (restart) {
      next_probe = resume.next_probe;
      next_field = resume.next_field;
    } else {
      write_probes();
      write_fields(true);
    }
    auto last_checkpoint = std::chrono::steady_clock::now();
    auto checkpoint = [&] {
      auto scope = timers.scope("checkpoint");
      Checkpoint c = capture_checkpoint(scene, model, dt, *be, fluid.get(), fsetup, st);
      if (root)
        on_root(distributed, [&] {
          c.output = {
              probe_csv->bytes(), fluid_csv ? static_cast<std::int64_t>(std::ftell(fluid_csv)) : -1,
              fields->frames(),   fluid_out ? fluid_out->frames() : 0,
              next_probe,         next_field,
              last_probe_step,    last_field_step};
          checkpoints->write(c);
        });
      last_checkpoint = std::chrono::steady_clock::now();
    };
    // Every rank must take the same decision (the checkpoint is collective), but wall clocks
    // differ: under mpirun the interval is due once it is on every rank.
    auto interval_due = [&] {
      bool due = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_checkpoint)
                     .count() >= cks.every_seconds;
#ifdef QDEMSPH_HAVE_MPI
      if (distributed) due = world_all(due);
#endif
      return due;
    };
    const auto nsteps = static_cast<std::int64_t>(std::ceil(end / dt - 1e-9));
    for (std::int64_t n = st.steps() + 1; n <= nsteps; ++n) {
      st.step();
      const double t = st.time();
      // Periodic output only: the run's last row and frame follow the loop, so a checkpoint
      // taken at a run's last step continues exactly like one taken mid-run.
      if (probe_dt > 0 ? t >= next_probe - 1e-12 * end : n % 100 == 0) {
        write_probes();
        next_probe += probe_dt;
      }
      if (field_dt > 0 && t >= next_field - 1e-12 * end) {
        write_fields(true);
        next_field += field_dt;
      }
      if (checkpointing && ((cks.every_steps > 0 && n % cks.every_steps == 0) ||
                            (cks.every_seconds > 0 && interval_due())))
        checkpoint();
      progress.update(static_cast<double>(n) / nsteps, n, fmt::format("t = {:.4g} s", t).c_str());
    }
    st.check();
    progress.finish();
    if (probe_dt == 0 && last_probe_step != st.steps()) write_probes();
    if (last_field_step != st.steps()) write_fields(true);
    finish("completed", st.steps());
  } catch (const SimulationError& e) {
    progress.finish();
    summary["error"] = e.what();
    try {
      write_fields(true);  // final diagnostic snapshot
    } catch (...) {
    }
    finish("failed", st.steps());
    throw;
  }
  if (!opt.quiet && root)
    fmt::print("{}: {} steps, t = {:.6g} s, wall {:.2f} s; output in {}\n", scene.name, st.steps(),
               st.time(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count(),
               dir.string());
  return code;
}

void print_info(const Scene& scene) {
  const Model model = build_model(scene);
  auto be = make_host_backend();
  be->upload(model);
  const double dt = choose_dt(model, scene.run.dt, scene.run.dt_safety);
  fmt::print("scene      {}\n", scene.file.string());
  fmt::print("mode       {}\n", scene.run.mode == RunMode::Static ? "static" : "dynamic");
  std::optional<FluidSetup> fluid_setup;
  if (scene.fluid.present) {
    fluid_setup = build_fluid(scene.fluid, scene.gravity);
    if (scene.fluid.couple_bodies) add_solid_markers(*fluid_setup, model);
  }
  fmt::print("stages     {}\n", stages_of(model, fluid_setup ? &*fluid_setup : nullptr));
  fmt::print("bodies     {}\n", model.bodies.size());
  for (const auto& b : model.bodies)
    fmt::print("  {:<16} {:>9} vertices {:>10} tets{}\n", b.name, b.v_end - b.v_begin,
               b.t_end - b.t_begin, b.fixed ? "  (fixed: not integrated)" : "");
  fmt::print("sizes      {} vertices, {} tets, {} surface triangles\n", model.n_vertices(),
             model.n_tets(), model.surface.size());
  fmt::print(
      "dt         {:.4e} s (stability limit {:.4e} s{})\n", dt, model.dt_critical,
      scene.run.dt ? ", fixed by the scene" : fmt::format(", safety {}", scene.run.dt_safety));
  double H = dt;
  int k = 1;
  if (fluid_setup) {
    const double dtf = fluid_dt(*fluid_setup);
    H = fluid_step(model, scene, dt, dtf, k);
    fmt::print(
        "fluid dt   {:.4e} s (CFL/force/viscous limit at the start {:.4e} s); {} solid "
        "step(s) per fluid step\n",
        H, dtf, k);
  }
  if (scene.run.mode == RunMode::Dynamic)
    fmt::print("steps      {} to t = {} s\n",
               static_cast<std::int64_t>(std::ceil(scene.run.end_time / H - 1e-9)),
               scene.run.end_time);
  fmt::print("memory     {:.1f} MiB of solver state ({:.0f} bytes per tet)\n",
             be->device_bytes() / 1048576.0,
             model.n_tets() ? static_cast<double>(be->device_bytes()) / model.n_tets() : 0.0);
  const GpuInfo gpu = gpu_info();
  fmt::print("backend    {} (run.backend; cuda {})\n", scene.run.backend,
             gpu.available ? "available" : "not available");
  if (gpu.available)
    fmt::print("gpu        {}; this scene's state would use {:.1f} % of it\n", gpu_summary(gpu),
               100.0 * be->device_bytes() / static_cast<double>(gpu.free_bytes));
  else
    fmt::print("gpu        {}\n", gpu_summary(gpu));
}

void export_meshes(const Scene& scene, const std::filesystem::path& dir) {
  const Model model = build_model(scene);
  std::filesystem::create_directories(dir);
  for (const auto& b : model.bodies) {
    TetMesh m;
    m.points.assign(model.X.begin() + b.v_begin, model.X.begin() + b.v_end);
    for (std::int64_t t = b.t_begin; t < b.t_end; ++t) {
      auto tv = model.tets[t];
      for (auto& v : tv) v -= static_cast<std::int32_t>(b.v_begin);
      m.tets.push_back(tv);
    }
    write_gmsh(dir / (b.name + ".msh"), m);
    fmt::print("{}: {} vertices, {} tets -> {}\n", b.name, m.points.size(), m.tets.size(),
               (dir / (b.name + ".msh")).string());
  }
}

}  // namespace qdemsph
