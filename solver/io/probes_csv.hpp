// probes.csv: one row per probe sample, flushed at once so a crashed or running simulation
// can be plotted.
//
// Columns: time, then <name>_x,<name>_y,<name>_z for each probe (a region-averaged
// displacement or a centre of mass, in scene order), then the energies kinetic, strain,
// potential, dissipated, contact, contact_dissipated and total = their sum
// (physics/energies.hpp defines them).
// Numbers are written as %.10e.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/vec.hpp"
#include "physics/energies.hpp"

namespace qdemsph {

class ProbeWriter {
 public:
  // Creates DIR (if needed) and DIR/probes.csv (truncating) and writes the header; with
  // resume_bytes >= 0 (a restart) continues the existing file after its first resume_bytes
  // bytes instead. Throws InputError when the folder is not writable.
  ProbeWriter(const std::filesystem::path& dir, std::vector<std::string> probe_names,
              std::int64_t resume_bytes = -1);
  ~ProbeWriter();
  ProbeWriter(const ProbeWriter&) = delete;
  ProbeWriter& operator=(const ProbeWriter&) = delete;

  // One row; `values` has one Vec3 per probe, in the order of the names given.
  void write(double time, std::span<const Vec3> values, const Energies& energies);

  const std::filesystem::path& path() const { return path_; }
  long rows() const { return rows_; }
  std::int64_t bytes() const;  // the file's length so far (for checkpoints)

 private:
  std::filesystem::path path_;
  std::vector<std::string> names_;
  std::FILE* file_ = nullptr;
  long rows_ = 0;
};

}  // namespace qdemsph
