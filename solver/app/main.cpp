// The qdemsph command line: run | info | mesh | version.
// Exit codes: 0 success, 1 internal error, 2 bad input, 3 static solve not converged,
// 4 simulation failed (NaN, inverted tet, instability).
#include <fmt/format.h>

#include <CLI/CLI.hpp>

#include "app/run_scene.hpp"
#include "core/error.hpp"
#include "core/gpu_info.hpp"
#include "core/memory.hpp"
#include "io/scene_yaml.hpp"
#ifdef QDEMSPH_HAVE_MPI
#include "parallel/world.hpp"
#endif

int main(int argc, char** argv) {
  using namespace qdemsph;
#ifdef QDEMSPH_HAVE_MPI
  // Under mpirun every rank runs this; errors of the scene and the simulation are seen by all
  // ranks alike (rank 0 reports them), any other error ends every rank (world_abort).
  const World& mpi = world_start(&argc, &argv);
  struct StopMpi {
    ~StopMpi() { world_stop(); }
  } stop_mpi;
  const bool report = mpi.root();
  auto internal = [&](int code) {
    if (mpi.size > 1) world_abort(code);
    return code;
  };
#else
  const bool report = true;
  auto internal = [](int code) { return code; };
#endif
  CLI::App app{"qdemsph: QDEM viscoelastic bodies with polygon contact and WCSPH fluid"};
  app.require_subcommand(1);

  std::string scene_file;
  std::vector<std::string> overrides;
  auto add_scene = [&](CLI::App* sub) {
    sub->add_option("scene", scene_file, "scene file (YAML, see docs/scene-format.md)")->required();
    sub->add_option("--set", overrides, "override a scene key: dotted.key=yaml_value (repeatable)");
  };

  RunOptions ropt;
  std::string out_dir, backend, restart;
  auto* run = app.add_subcommand("run", "run a scene");
  add_scene(run);
  run->add_option("-o,--out", out_dir, "output folder (default: the scene's output.dir)");
  run->add_option("-b,--backend", backend, "cpu or cuda (default: the scene's run.backend)");
  run->add_flag("-q,--quiet", ropt.quiet, "no progress line or final message");
  run->add_option("--restart", restart,
                  "continue from a checkpoint file, or 'latest': the newest in the run's "
                  "checkpoint folder (output.checkpoint)");

  auto* info = app.add_subcommand("info", "print the stages, sizes, dt and memory of a scene");
  add_scene(info);

  std::string mesh_dir;
  auto* mesh = app.add_subcommand("mesh", "export each body's mesh as Gmsh .msh");
  add_scene(mesh);
  mesh->add_option("-o,--out", mesh_dir, "output folder")->required();

  auto* version = app.add_subcommand("version", "print version and build options");

  CLI11_PARSE(app, argc, argv);
  try {
    if (version->parsed()) {
#ifdef QDEMSPH_HAVE_MPI
      const char* mpi_note = "; mpi";  // `mpirun -np N qdemsph run` runs distributed
#else
      const char* mpi_note = "";
#endif
#ifdef QDEMSPH_HAVE_CUDA
      fmt::print("qdemsph 0.1.0 (double precision; backends: cpu, cuda{})\ngpu: {}\n", mpi_note,
                 gpu_summary(gpu_info()));
#else
      fmt::print("qdemsph 0.1.0 (double precision; backends: cpu{})\n", mpi_note);
#endif
      return 0;
    }
    const Scene scene = load_scene(scene_file, overrides);
    if (run->parsed()) {
      if (!out_dir.empty()) ropt.out = out_dir;
      if (!backend.empty()) ropt.backend = backend;
      if (!restart.empty()) ropt.restart = restart;
      return run_scene(scene, ropt);
    }
    if (info->parsed()) print_info(scene);
    if (mesh->parsed()) export_meshes(scene, mesh_dir);
    return 0;
  } catch (const InputError& e) {
    if (report) fmt::print(stderr, "qdemsph: error: {}\n", e.what());
    return 2;
  } catch (const SimulationError& e) {
    if (report) fmt::print(stderr, "qdemsph: simulation failed: {}\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    fmt::print(stderr, "qdemsph: internal error: {}\n", e.what());
    return internal(1);
  }
}
