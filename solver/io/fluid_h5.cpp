#include "io/fluid_h5.hpp"

#include <fmt/format.h>
#include <hdf5.h>

#include <stdexcept>

#include "core/error.hpp"
#include "io/h5_file.hpp"
#include "io/json.hpp"

namespace qdemsph {
namespace {

void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: " + what + " failed");
}

void write_set(hid_t parent, const char* name, hid_t type, const void* data, hsize_t rows,
               hsize_t cols) {
  const hsize_t dims[2] = {rows, cols};
  const hid_t space = H5Screate_simple(cols ? 2 : 1, dims, nullptr);
  if (space < 0) throw std::runtime_error("HDF5: H5Screate failed");
  const hid_t set = H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Sclose(space);
  if (set < 0) throw std::runtime_error(std::string("HDF5: create ") + name + " failed");
  const herr_t st = rows > 0 ? H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) : 0;
  H5Dclose(set);
  check(st, name);
}

template <class T>
void write_attr(hid_t obj, const char* name, hid_t type, const T& value) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  const herr_t st = H5Awrite(attr, type, &value);
  H5Aclose(attr);
  H5Sclose(space);
  check(st, name);
}

}  // namespace

FluidWriter::FluidWriter(const std::filesystem::path& dir, std::int64_t resume_frames)
    : h5_path_(dir / "fluid.h5"), xdmf_path_(dir / "fluid.xdmf") {
  ensure_output_dir(dir);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (resume_frames >= 0) {
    file_ = h5::reopen_series(h5_path_, static_cast<std::size_t>(resume_frames), times_, "position",
                              counts_);
    if (file_ >= 0) {
      write_file_atomically(xdmf_path_, xdmf());
      return;
    }
    h5::set_aside(h5_path_, resume_frames);
  }
  file_ = H5Fcreate(h5_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) throw InputError("cannot create '" + h5_path_.string() + "'");
  const hid_t g = H5Gcreate2(file_, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) throw std::runtime_error("HDF5: create /steps failed");
  H5Gclose(g);
  write_file_atomically(xdmf_path_, xdmf());
}

FluidWriter::~FluidWriter() {
  if (file_ >= 0) H5Fclose(file_);
}

void FluidWriter::write(double time, std::int64_t step, std::span<const Vec3> x,
                        std::span<const Vec3> v, std::span<const double> pressure,
                        std::span<const double> density, std::span<const std::uint8_t> type,
                        std::span<const std::uint64_t> id) {
  const std::size_t n = x.size();
  const std::string group = fmt::format("/steps/{:06d}", times_.size());
  const hid_t g = H5Gcreate2(file_, group.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) throw std::runtime_error("HDF5: create " + group + " failed");
  try {
    write_attr(g, "time", H5T_NATIVE_DOUBLE, time);
    write_attr(g, "step", H5T_NATIVE_INT64, step);
    write_set(g, "position", H5T_NATIVE_DOUBLE, x.data(), n, 3);
    write_set(g, "velocity", H5T_NATIVE_DOUBLE, v.data(), n, 3);
    write_set(g, "pressure", H5T_NATIVE_DOUBLE, pressure.data(), n, 0);
    write_set(g, "density", H5T_NATIVE_DOUBLE, density.data(), n, 0);
    std::vector<std::int32_t> t(type.begin(), type.end());
    write_set(g, "type", H5T_NATIVE_INT32, t.data(), n, 0);
    std::vector<std::int64_t> i64(id.begin(), id.end());
    write_set(g, "id", H5T_NATIVE_INT64, i64.data(), n, 0);
  } catch (...) {
    H5Gclose(g);
    throw;
  }
  H5Gclose(g);
  times_.push_back(time);
  counts_.push_back(n);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush " + h5_path_.string());
  write_file_atomically(xdmf_path_, xdmf());
}

std::string FluidWriter::xdmf() const {
  const std::string h5 = h5_path_.filename().string();
  std::string s = "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n";
  s += "  <Grid Name=\"fluid\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto item = [&](const std::string& dims, const char* type, int prec, const std::string& path) {
    return fmt::format(
        "     <DataItem Dimensions=\"{}\" NumberType=\"{}\" Precision=\"{}\" "
        "Format=\"HDF\">{}:{}</DataItem>\n",
        dims, type, prec, h5, path);
  };
  for (std::size_t k = 0; k < times_.size(); ++k) {
    const std::size_t n = counts_[k];
    const std::string p = fmt::format("/steps/{:06d}/", k);
    s += fmt::format("   <Grid Name=\"frame_{:06d}\" GridType=\"Uniform\">\n", k);
    s += fmt::format("    <Time Value=\"{}\"/>\n", times_[k]);
    s += fmt::format("    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"{}\"/>\n", n);
    s += "    <Geometry GeometryType=\"XYZ\">\n" +
         item(fmt::format("{} 3", n), "Float", 8, p + "position") + "    </Geometry>\n";
    auto attr = [&](const char* name, const char* kind, const std::string& dims, const char* type,
                    int prec) {
      s += fmt::format("    <Attribute Name=\"{}\" AttributeType=\"{}\" Center=\"Node\">\n", name,
                       kind) +
           item(dims, type, prec, p + name) + "    </Attribute>\n";
    };
    attr("velocity", "Vector", fmt::format("{} 3", n), "Float", 8);
    attr("pressure", "Scalar", fmt::format("{}", n), "Float", 8);
    attr("density", "Scalar", fmt::format("{}", n), "Float", 8);
    attr("type", "Scalar", fmt::format("{}", n), "Int", 4);
    attr("id", "Scalar", fmt::format("{}", n), "Int", 8);
    s += "   </Grid>\n";
  }
  s += "  </Grid>\n </Domain>\n</Xdmf>\n";
  return s;
}

}  // namespace qdemsph
