// HDF5 + XDMF field writer (see fields_h5.hpp). Serial HDF5 C API; one dataset per field per
// frame keeps the layout trivially readable from h5py and ParaView alike.
#include "io/fields_h5.hpp"

#include <fmt/format.h>
#include <hdf5.h>

#include <stdexcept>
#include <type_traits>

#include "core/error.hpp"
#include "io/h5_file.hpp"
#include "io/json.hpp"

namespace qdemsph {
namespace {

static_assert(std::is_same_v<hid_t, int64_t>, "FieldWriter stores hid_t as int64_t");
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 arrays are written as (N,3) doubles");

using h5::check;
using h5::Handle;
using h5::write_dataset;
using h5::write_string_attribute;

std::string frame_name(size_t k) { return fmt::format("{:06d}", k); }

}  // namespace

FieldWriter::FieldWriter(const std::filesystem::path& dir, std::span<const Vec3> points,
                         std::span<const std::array<int32_t, 4>> tets,
                         std::span<const int32_t> vertex_body, int64_t resume_frames)
    : h5_path_(dir / "fields.h5"),
      xdmf_path_(dir / "fields.xdmf"),
      reference_(points.begin(), points.end()),
      num_tets_(tets.size()) {
  if (vertex_body.size() != points.size())
    throw std::logic_error("FieldWriter: vertex_body size differs from points");
  ensure_output_dir(dir);
  // HDF5 prints its own error stack to stderr by default; we report failures ourselves.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (resume_frames >= 0) {
    std::vector<size_t> unused;
    file_ = h5::reopen_series(h5_path_, static_cast<size_t>(resume_frames), times_, "", unused);
    bool fits = false;
    try {
      fits = file_ >= 0 && h5::rows(file_, "mesh/points") == points.size() &&
             h5::rows(file_, "mesh/tets") == tets.size();
    } catch (const std::runtime_error&) {
    }
    if (fits) {
      write_file_atomically(xdmf_path_, xdmf());
      return;
    }
    if (file_ >= 0) H5Fclose(file_);
    times_.clear();
    h5::set_aside(h5_path_, resume_frames);
  }
  file_ = H5Fcreate(h5_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) throw InputError("cannot create '" + h5_path_.string() + "'");

  Handle mesh(H5Gcreate2(file_, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
              "create /mesh");
  write_dataset(mesh.id, "points", H5T_NATIVE_DOUBLE, points.data(), points.size(), 3);
  // int64 on disk: meshes beyond 2^31 vertices must stay readable with the same layout.
  std::vector<int64_t> tets64(tets.size() * 4);
  for (size_t t = 0; t < tets.size(); ++t)
    for (int j = 0; j < 4; ++j) tets64[4 * t + j] = tets[t][j];
  write_dataset(mesh.id, "tets", H5T_NATIVE_INT64, tets64.data(), tets.size(), 4);
  write_dataset(mesh.id, "body", H5T_NATIVE_INT32, vertex_body.data(), vertex_body.size(), 0);
  Handle steps(H5Gcreate2(file_, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
               "create /steps");
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush");
  write_file_atomically(xdmf_path_, xdmf());
}

FieldWriter::~FieldWriter() {
  if (file_ >= 0) H5Fclose(file_);
}

void FieldWriter::write(double time, int64_t step, std::span<const Vec3> positions,
                        std::span<const Vec3> velocities,
                        std::span<const std::array<double, 6>> stress,
                        std::span<const double> von_mises) {
  const size_t n = reference_.size();
  if (positions.size() != n || velocities.size() != n || stress.size() != num_tets_ ||
      von_mises.size() != num_tets_)
    throw std::logic_error(fmt::format(
        "FieldWriter::write: sizes {}/{}/{}/{} do not match the mesh ({} vertices, {} tets)",
        positions.size(), velocities.size(), stress.size(), von_mises.size(), n, num_tets_));

  const std::string group = "/steps/" + frame_name(times_.size());
  Handle g(H5Gcreate2(file_, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
           "create " + group);
  h5::write_attribute<double>(g.id, "time", time);
  h5::write_attribute<std::int64_t>(g.id, "step", step);

  write_dataset(g.id, "position", H5T_NATIVE_DOUBLE, positions.data(), n, 3);
  std::vector<Vec3> disp(n);
  for (size_t i = 0; i < n; ++i) disp[i] = positions[i] - reference_[i];
  write_dataset(g.id, "displacement", H5T_NATIVE_DOUBLE, disp.data(), n, 3);
  write_dataset(g.id, "velocity", H5T_NATIVE_DOUBLE, velocities.data(), n, 3);

  // Voigt (xx,yy,zz,yz,xz,xy) -> XDMF Tensor6 (xx,xy,xz,yy,yz,zz).
  std::vector<double> t6(6 * num_tets_);
  for (size_t e = 0; e < num_tets_; ++e) {
    const auto& s = stress[e];
    const double row[6] = {s[0], s[5], s[4], s[1], s[3], s[2]};
    std::copy(row, row + 6, t6.begin() + static_cast<long>(6 * e));
  }
  write_dataset(g.id, "stress", H5T_NATIVE_DOUBLE, t6.data(), num_tets_, 6);
  {
    Handle set(H5Dopen2(g.id, "stress", H5P_DEFAULT), H5Dclose, "open stress");
    write_string_attribute(set.id, "components", "xx,xy,xz,yy,yz,zz");
  }
  write_dataset(g.id, "von_mises", H5T_NATIVE_DOUBLE, von_mises.data(), num_tets_, 0);

  times_.push_back(time);
  // Flush before publishing the XDMF, so every frame the XDMF names is on disk.
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush " + h5_path_.string());
  write_file_atomically(xdmf_path_, xdmf());
}

std::string FieldWriter::xdmf() const {
  const std::string h5 = h5_path_.filename().string();  // relative: the folder can be moved
  const size_t n = reference_.size(), m = num_tets_;
  std::string x;
  x += "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n";
  x += "  <Grid Name=\"qdemsph\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto item = [&](const std::string& dims, const char* type, int precision,
                  const std::string& path) {
    return fmt::format(
        "     <DataItem Dimensions=\"{}\" NumberType=\"{}\" Precision=\"{}\" "
        "Format=\"HDF\">{}:{}</DataItem>\n",
        dims, type, precision, h5, path);
  };
  auto attribute = [&](const char* name, const char* type, const char* center,
                       const std::string& dims, const char* number, int precision,
                       const std::string& path) {
    return fmt::format("    <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"{}\">\n", name,
                       type, center) +
           item(dims, number, precision, path) + "    </Attribute>\n";
  };
  for (size_t k = 0; k < times_.size(); ++k) {
    const std::string s = "/steps/" + frame_name(k) + "/";
    x += fmt::format("   <Grid Name=\"frame_{}\" GridType=\"Uniform\">\n", frame_name(k));
    x += fmt::format("    <Time Value=\"{}\"/>\n", times_[k]);
    x += fmt::format("    <Topology TopologyType=\"Tetrahedron\" NumberOfElements=\"{}\">\n", m);
    x += item(fmt::format("{} 4", m), "Int", 8, "/mesh/tets") + "    </Topology>\n";
    x += "    <Geometry GeometryType=\"XYZ\">\n";
    x += item(fmt::format("{} 3", n), "Float", 8, s + "position") + "    </Geometry>\n";
    x += attribute("displacement", "Vector", "Node", fmt::format("{} 3", n), "Float", 8,
                   s + "displacement");
    x +=
        attribute("velocity", "Vector", "Node", fmt::format("{} 3", n), "Float", 8, s + "velocity");
    x += attribute("body", "Scalar", "Node", fmt::format("{}", n), "Int", 4, "/mesh/body");
    x += attribute("stress", "Tensor6", "Cell", fmt::format("{} 6", m), "Float", 8, s + "stress");
    x +=
        attribute("von_mises", "Scalar", "Cell", fmt::format("{}", m), "Float", 8, s + "von_mises");
    x += "   </Grid>\n";
  }
  x += "  </Grid>\n </Domain>\n</Xdmf>\n";
  return x;
}

}  // namespace qdemsph
