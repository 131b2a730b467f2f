// probes.csv writer (see probes_csv.hpp).
#include "io/probes_csv.hpp"

#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "io/json.hpp"

namespace qdemsph {

ProbeWriter::ProbeWriter(const std::filesystem::path& dir, std::vector<std::string> probe_names,
                         std::int64_t resume_bytes)
    : path_(dir / "probes.csv"), names_(std::move(probe_names)) {
  ensure_output_dir(dir);
  std::string header = "time";
  for (const auto& n : names_) header += "," + n + "_x," + n + "_y," + n + "_z";
  header += ",kinetic,strain,potential,dissipated,contact,contact_dissipated,total\n";
  if (resume_bytes >= 0) {
    file_ = reopen_for_append(path_, resume_bytes, header);
    return;
  }
  file_ = std::fopen(path_.c_str(), "w");
  if (!file_) throw InputError("cannot create '" + path_.string() + "': folder not writable");
  std::fputs(header.c_str(), file_);
  std::fflush(file_);
}

std::int64_t ProbeWriter::bytes() const { return std::ftell(file_); }

ProbeWriter::~ProbeWriter() {
  if (file_) std::fclose(file_);
}

void ProbeWriter::write(double time, std::span<const Vec3> values, const Energies& e) {
  if (values.size() != names_.size())
    throw std::logic_error("ProbeWriter::write: " + std::to_string(values.size()) + " values for " +
                           std::to_string(names_.size()) + " probes");
  std::fprintf(file_, "%.10e", time);
  for (const Vec3& v : values) std::fprintf(file_, ",%.10e,%.10e,%.10e", v.x, v.y, v.z);
  std::fprintf(file_, ",%.10e,%.10e,%.10e,%.10e,%.10e,%.10e,%.10e\n", e.kinetic, e.strain,
               e.potential, e.dissipated, e.contact, e.contact_dissipated, e.total());
  // Flushed per row: rows are rare next to steps, and a partial run stays plottable.
  if (std::fflush(file_) != 0)
    throw std::runtime_error("cannot write '" + path_.string() + "' (disk full?)");
  ++rows_;
}

}  // namespace qdemsph
