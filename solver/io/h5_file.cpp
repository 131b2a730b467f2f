#include "io/h5_file.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>
#include <type_traits>

namespace qdemsph::h5 {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 arrays are (N,3) doubles");

Handle::Handle(hid_t i, herr_t (*c)(hid_t), const std::string& what) : id(i), close(c) {
  if (id < 0) throw std::runtime_error("HDF5: " + what + " failed");
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: " + what + " failed");
}

template <>
hid_t native<double>() {
  return H5T_NATIVE_DOUBLE;
}
template <>
hid_t native<std::int32_t>() {
  return H5T_NATIVE_INT32;
}
template <>
hid_t native<std::int64_t>() {
  return H5T_NATIVE_INT64;
}
template <>
hid_t native<std::uint8_t>() {
  return H5T_NATIVE_UINT8;
}
template <>
hid_t native<std::uint64_t>() {
  return H5T_NATIVE_UINT64;
}

void write_dataset(hid_t parent, const char* name, hid_t type, const void* data, hsize_t rows,
                   hsize_t cols) {
  const hsize_t dims[2] = {rows, cols};
  Handle space(H5Screate_simple(cols ? 2 : 1, dims, nullptr), H5Sclose, "H5Screate");
  Handle set(H5Dcreate2(parent, name, type, space.id, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
             H5Dclose, std::string("create dataset ") + name);
  // An empty dataset has nothing to write; H5Dwrite rejects null data.
  if (rows > 0) check(H5Dwrite(set.id, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}

void write(hid_t parent, const char* name, const std::vector<Vec3>& v) {
  write_dataset(parent, name, H5T_NATIVE_DOUBLE, v.data(), v.size(), 3);
}

namespace {

// Opens `name` and checks its shape: (n) for cols = 0, (n, cols) otherwise. Returns n.
hsize_t open_shaped(hid_t parent, const char* name, hsize_t cols, hid_t& set) {
  set = H5Dopen2(parent, name, H5P_DEFAULT);
  if (set < 0) throw std::runtime_error(std::string("dataset '") + name + "' is missing");
  const hid_t space = H5Dget_space(set);
  hsize_t dims[2] = {0, 0};
  const int rank = H5Sget_simple_extent_ndims(space);
  if (rank >= 1 && rank <= 2) H5Sget_simple_extent_dims(space, dims, nullptr);
  H5Sclose(space);
  if (rank != (cols ? 2 : 1) || (cols && dims[1] != cols)) {
    H5Dclose(set);
    throw std::runtime_error(std::string("dataset '") + name + "' has an unexpected shape");
  }
  return dims[0];
}

// `out` gets `per_row` elements per row (a Vec3 is one element of a 3-column row).
template <class T>
void read_into(hid_t parent, const char* name, hid_t type, hsize_t cols, std::size_t per_row,
               std::vector<T>& out) {
  hid_t set = -1;
  const hsize_t n = open_shaped(parent, name, cols, set);
  Handle guard(set, H5Dclose, name);
  out.resize(n * per_row);
  if (n > 0) check(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), name);
}

}  // namespace

template <class T>
std::vector<T> read(hid_t parent, const char* name, hsize_t cols) {
  std::vector<T> v;
  read_into(parent, name, native<T>(), cols, cols ? cols : 1, v);
  return v;
}
template std::vector<double> read<double>(hid_t, const char*, hsize_t);
template std::vector<std::int32_t> read<std::int32_t>(hid_t, const char*, hsize_t);
template std::vector<std::int64_t> read<std::int64_t>(hid_t, const char*, hsize_t);
template std::vector<std::uint8_t> read<std::uint8_t>(hid_t, const char*, hsize_t);
template std::vector<std::uint64_t> read<std::uint64_t>(hid_t, const char*, hsize_t);

std::vector<Vec3> read_vec3(hid_t parent, const char* name) {
  std::vector<Vec3> v;
  read_into(parent, name, H5T_NATIVE_DOUBLE, 3, 1, v);
  return v;
}

hsize_t rows(hid_t parent, const char* name) {
  Handle set(H5Dopen2(parent, name, H5P_DEFAULT), H5Dclose, std::string("open ") + name);
  Handle space(H5Dget_space(set.id), H5Sclose, "H5Dget_space");
  hsize_t dims[2] = {0, 0};
  if (H5Sget_simple_extent_ndims(space.id) < 1) return 0;
  H5Sget_simple_extent_dims(space.id, dims, nullptr);
  return dims[0];
}

template <class T>
void write_attribute(hid_t obj, const char* name, const T& value) {
  Handle space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Handle attr(H5Acreate2(obj, name, native<T>(), space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
              name);
  check(H5Awrite(attr.id, native<T>(), &value), name);
}
template void write_attribute<double>(hid_t, const char*, const double&);
template void write_attribute<std::int64_t>(hid_t, const char*, const std::int64_t&);

void write_string_attribute(hid_t obj, const char* name, const std::string& value) {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
  check(H5Tset_size(type.id, value.empty() ? 1 : value.size()), "H5Tset_size");
  Handle space(H5Screate(H5S_SCALAR), H5Sclose, "H5Screate");
  Handle attr(H5Acreate2(obj, name, type.id, space.id, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, name);
  const std::string padded = value.empty() ? std::string(1, '\0') : value;
  check(H5Awrite(attr.id, type.id, padded.data()), name);
}

template <class T>
T read_attribute(hid_t obj, const char* name) {
  Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  T value{};
  check(H5Aread(attr.id, native<T>(), &value), std::string("read attribute ") + name);
  return value;
}
template double read_attribute<double>(hid_t, const char*);
template std::int64_t read_attribute<std::int64_t>(hid_t, const char*);

std::string read_string_attribute(hid_t obj, const char* name) {
  Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose, std::string("attribute ") + name);
  Handle type(H5Aget_type(attr.id), H5Tclose, "H5Aget_type");
  if (H5Tget_class(type.id) != H5T_STRING || H5Tis_variable_str(type.id) > 0)
    throw std::runtime_error(std::string("attribute '") + name + "' is not a fixed-length string");
  const std::size_t n = H5Tget_size(type.id);
  std::string s(n, '\0');
  Handle mem(H5Tcopy(H5T_C_S1), H5Tclose, "H5Tcopy");
  check(H5Tset_size(mem.id, n), "H5Tset_size");
  check(H5Aread(attr.id, mem.id, s.data()), std::string("read attribute ") + name);
  s.resize(s.find('\0') == std::string::npos ? n : s.find('\0'));
  return s;
}

bool has_attribute(hid_t obj, const char* name) { return H5Aexists(obj, name) > 0; }

bool exists(hid_t parent, const char* path) { return H5Lexists(parent, path, H5P_DEFAULT) > 0; }

hid_t reopen_series(const std::filesystem::path& path, std::size_t keep, std::vector<double>& times,
                    const char* rows_of, std::vector<std::size_t>& rows_out) {
  times.clear();
  rows_out.clear();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return -1;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file < 0) return -1;
  try {
    if (!exists(file, "steps")) throw std::runtime_error("no /steps");
    for (std::size_t k = 0; k < keep; ++k) {
      const std::string g = fmt::format("steps/{:06d}", k);
      Handle grp(H5Gopen2(file, g.c_str(), H5P_DEFAULT), H5Gclose, "open " + g);
      times.push_back(read_attribute<double>(grp.id, "time"));
      if (rows_of && *rows_of) rows_out.push_back(rows(grp.id, rows_of));
    }
    for (std::size_t k = keep;; ++k) {
      const std::string g = fmt::format("steps/{:06d}", k);
      if (!exists(file, g.c_str())) break;
      check(H5Ldelete(file, g.c_str(), H5P_DEFAULT), "delete " + g);
    }
    check(H5Fflush(file, H5F_SCOPE_GLOBAL), "flush");
  } catch (const std::exception&) {
    H5Fclose(file);
    times.clear();
    rows_out.clear();
    return -1;
  }
  return file;
}

void set_aside(const std::filesystem::path& path, std::int64_t frames) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return;
  const std::filesystem::path aside = path.string() + ".unreadable";
  std::filesystem::rename(path, aside, ec);
  fmt::print(stderr,
             "qdemsph: warning: '{}' cannot be continued after frame {} (damaged by a kill during "
             "a write?); {}, and a new file begins at the restart\n",
             path.string(), frames,
             ec ? "it is overwritten" : "it was renamed to '" + aside.string() + "'");
}

}  // namespace qdemsph::h5
