// Checkpoint/restart of a dynamic run: the state between two steps taken from the backend,
// the fluid stage and the stepper (capture), checked against a scene and put back (restore),
// so that N steps + restart + N steps is bit-identical to 2N steps on the CPU backend, on any
// number of ranks (the same file from any rank count, restarted on any rank count). The
// file format is io/checkpoint_h5.hpp; the run driver (app/run_scene.cpp) adds the outputs.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "integrate/backend.hpp"
#include "integrate/stepper.hpp"
#include "io/checkpoint_h5.hpp"
#include "io/scene.hpp"
#include "model/model.hpp"
#include "sph/fluid_setup.hpp"
#include "sph/fluid_stage.hpp"

namespace qdemsph {

using Fingerprint = std::vector<std::pair<std::string, std::string>>;

// What a checkpoint must match to continue this scene: sizes, global ids, the mesh, every
// material, masses and constraints, loads, gravity and damping, contact and fluid parameters,
// probes and dt. Items are readable where short ("material 'rubber'": its values) and hashes
// (FNV-1a 64) of the arrays otherwise. end_time, output intervals, backend and threads may
// change between runs.
Fingerprint make_fingerprint(const Scene& scene, const Model& model, double dt,
                             const FluidSetup* fluid);

// One line per differing item: "ITEM: checkpoint has A, the scene has B" (or lacks it).
std::vector<std::string> fingerprint_differences(const Fingerprint& saved, const Fingerprint& now);

// The run's state after `stepper.steps()` steps; output fields are left to the caller.
// Collective with a distributed backend (parallel/distributed_backend.hpp): the state is
// gathered to rank 0, which gets the same checkpoint as one rank (other ranks: no state).
Checkpoint capture_checkpoint(const Scene& scene, const Model& model, double dt, Backend& backend,
                              FluidStage* fluid, const FluidSetup* fluid_setup,
                              const Stepper& stepper);

// InputError naming `source` and every fingerprint item of c that differs from the scene's.
void check_checkpoint(const Checkpoint& c, const std::string& source, const Scene& scene,
                      const Model& model, double dt, const FluidSetup* fluid_setup);

// Checks c against the scene (check_checkpoint) and puts the
// state back into the backend, the fluid stage and the stepper's clock. Call after the
// Stepper is constructed (its first force evaluation would overwrite the restored forces).
// With a distributed backend every rank passes the whole checkpoint (collective): each takes a
// share, repartitioned for this number of ranks.
void restore_checkpoint(const Checkpoint& c, const std::string& source, const Scene& scene,
                        const Model& model, double dt, Backend& backend, FluidStage* fluid,
                        const FluidSetup* fluid_setup, Stepper& stepper);

}  // namespace qdemsph
