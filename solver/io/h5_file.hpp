// Small helpers over the serial HDF5 C API shared by the writers and readers of io/: scoped
// handles, typed whole-dataset and scalar-attribute I/O, and reopening a frame series
// (/steps/<k:06d>) to append after a restart. Include only from .cpp files (pulls in hdf5.h).
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/vec.hpp"

namespace qdemsph::h5 {

// Closes an HDF5 handle at scope exit; throws std::runtime_error naming `what` for id < 0.
struct Handle {
  hid_t id;
  herr_t (*close)(hid_t);
  Handle(hid_t i, herr_t (*c)(hid_t), const std::string& what);
  ~Handle() {
    if (id >= 0) close(id);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
};

void check(herr_t status, const std::string& what);

// The HDF5 native type of T (double, int32, int64, uint8, uint64).
template <class T>
hid_t native();

// A (rows) or (rows, cols) dataset; cols = 0: one dimension.
void write_dataset(hid_t parent, const char* name, hid_t type, const void* data, hsize_t rows,
                   hsize_t cols);
template <class T>
void write(hid_t parent, const char* name, const std::vector<T>& v) {
  write_dataset(parent, name, native<T>(), v.data(), v.size(), 0);
}
void write(hid_t parent, const char* name, const std::vector<Vec3>& v);  // (N, 3)

// Whole datasets back, row-major; std::runtime_error naming the dataset when it is missing or
// of another shape: (N) for cols = 0, (N, cols) otherwise; read_vec3 reads an (N, 3) one.
template <class T>
std::vector<T> read(hid_t parent, const char* name, hsize_t cols = 0);
std::vector<Vec3> read_vec3(hid_t parent, const char* name);
// Rows of a dataset (its first dimension).
hsize_t rows(hid_t parent, const char* name);

template <class T>
void write_attribute(hid_t obj, const char* name, const T& value);
void write_string_attribute(hid_t obj, const char* name, const std::string& value);
template <class T>
T read_attribute(hid_t obj, const char* name);
std::string read_string_attribute(hid_t obj, const char* name);
bool has_attribute(hid_t obj, const char* name);
bool exists(hid_t parent, const char* path);

// Reopens `path` (a series file with /steps/<k:06d> groups) for appending after frame `keep`:
// frames >= keep are deleted, `times` receives the kept frames' "time" attributes and `rows`
// the row count of their dataset `rows_of` (empty: not read). Returns the open file, or -1
// when the file is missing, unreadable or holds fewer than `keep` frames.
hid_t reopen_series(const std::filesystem::path& path, std::size_t keep, std::vector<double>& times,
                    const char* rows_of, std::vector<std::size_t>& rows);

// A series file that cannot be continued after `frames` frames: renamed to PATH.unreadable
// (replacing an older one) with a warning on stderr, so that a new file can take its place.
void set_aside(const std::filesystem::path& path, std::int64_t frames);

}  // namespace qdemsph::h5
