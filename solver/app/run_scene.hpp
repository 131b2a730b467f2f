// Runs a scene end to end: model, backend, initial static solve (preload) or static mode,
// the time loop, probes, field snapshots, progress and summary.json.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "io/scene.hpp"

namespace qdemsph {

struct RunOptions {
  std::optional<std::filesystem::path> out;  // overrides output.dir
  std::optional<std::string> backend;        // overrides run.backend
  // Continue from a checkpoint file, or "latest": the newest in the run's checkpoint folder.
  std::optional<std::string> restart;
  bool quiet = false;
};

// Returns the process exit code: 0 completed/converged, 3 static solve not converged.
// With output.checkpoint a dynamic run writes checkpoints (io/checkpoint_h5.hpp); a restart
// checks the checkpoint against the scene before touching any output, then continues
// probes.csv, fluid.csv, fields.h5 and fluid.h5 from the checkpoint's rows and frames.
// A SimulationError is reported in summary.json (status "failed") with a final diagnostic
// snapshot, then rethrown.
int run_scene(const Scene& scene, const RunOptions& options);

// `qdemsph info`: stages the scene needs, sizes, dt and memory.
void print_info(const Scene& scene);

// `qdemsph mesh`: each body's mesh as DIR/<body>.msh.
void export_meshes(const Scene& scene, const std::filesystem::path& dir);

}  // namespace qdemsph
