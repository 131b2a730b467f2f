// Output writers: HDF5/XDMF fields read back through the HDF5 API, probes.csv layout, JSON
// escaping and double round trip, and the "output folder not writable" error.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/error.hpp"
#include "io/fields_h5.hpp"
#include "io/json.hpp"
#include "io/probes_csv.hpp"

namespace qdemsph {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("qdemsph_test_output_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  return d;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<double> read_doubles(hid_t file, const std::string& path, std::vector<hsize_t>* dims) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << path;
  const hid_t space = H5Dget_space(set);
  const int rank = H5Sget_simple_extent_ndims(space);
  dims->assign(static_cast<size_t>(rank), 0);
  H5Sget_simple_extent_dims(space, dims->data(), nullptr);
  hsize_t count = 1;
  for (hsize_t d : *dims) count *= d;
  std::vector<double> v(count);
  EXPECT_GE(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
  H5Sclose(space);
  H5Dclose(set);
  return v;
}

double read_time(hid_t file, const std::string& group) {
  const hid_t g = H5Gopen2(file, group.c_str(), H5P_DEFAULT);
  const hid_t a = H5Aopen(g, "time", H5P_DEFAULT);
  double t = -1;
  H5Aread(a, H5T_NATIVE_DOUBLE, &t);
  H5Aclose(a);
  H5Gclose(g);
  return t;
}

// One tet plus a stray vertex of a second body: enough to check every dataset's layout.
struct TinyMesh {
  std::vector<Vec3> points{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {5, 5, 5}};
  std::vector<std::array<int32_t, 4>> tets{{0, 1, 2, 3}};
  std::vector<int32_t> body{0, 0, 0, 0, 1};
};

TEST(FieldWriter, ThreeFramesReadBack) {
  const fs::path dir = fresh_dir("fields");
  TinyMesh mesh;
  {
    FieldWriter w(dir, mesh.points, mesh.tets, mesh.body);
    for (int k = 0; k < 3; ++k) {
      std::vector<Vec3> pos = mesh.points, vel(mesh.points.size());
      for (size_t i = 0; i < pos.size(); ++i) {
        pos[i].x += 0.1 * k;
        vel[i] = {double(k), double(i), -1.0};
      }
      // Voigt xx,yy,zz,yz,xz,xy = 1..6 (+10k)
      std::vector<std::array<double, 6>> stress{{1. + 10 * k, 2, 3, 4, 5, 6}};
      std::vector<double> vm{100.0 + k};
      w.write(0.5 * k, 1000 * k, pos, vel, stress, vm);
      EXPECT_EQ(w.frames(), k + 1);
      // The XDMF must be complete after every frame (a running simulation can be opened).
      EXPECT_NE(slurp(dir / "fields.xdmf").find(fmt::format("/steps/{:06d}/position", k)),
                std::string::npos);
    }
  }
  const hid_t f = H5Fopen((dir / "fields.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  std::vector<hsize_t> dims;
  EXPECT_EQ(read_doubles(f, "/mesh/points", &dims)[13], 5.0);
  EXPECT_EQ(dims, (std::vector<hsize_t>{5, 3}));
  {
    const hid_t set = H5Dopen2(f, "/mesh/tets", H5P_DEFAULT);
    const hid_t type = H5Dget_type(set);
    EXPECT_EQ(H5Tget_size(type), 8u);  // int64 on disk
    int64_t t[4];
    H5Dread(set, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, t);
    EXPECT_EQ(t[3], 3);
    H5Tclose(type);
    H5Dclose(set);
  }
  for (int k = 0; k < 3; ++k) {
    const std::string g = fmt::format("/steps/{:06d}", k);
    EXPECT_DOUBLE_EQ(read_time(f, g), 0.5 * k);
    const auto pos = read_doubles(f, g + "/position", &dims);
    EXPECT_EQ(dims, (std::vector<hsize_t>{5, 3}));
    EXPECT_DOUBLE_EQ(pos[3], 1.0 + 0.1 * k);
    const auto disp = read_doubles(f, g + "/displacement", &dims);
    EXPECT_NEAR(disp[3], 0.1 * k, 1e-15);
    EXPECT_EQ(disp[4], 0.0);
    const auto vel = read_doubles(f, g + "/velocity", &dims);
    EXPECT_EQ(vel[3 * 4 + 1], 4.0);
    const auto s = read_doubles(f, g + "/stress", &dims);
    EXPECT_EQ(dims, (std::vector<hsize_t>{1, 6}));
    // Stored in Tensor6 order xx,xy,xz,yy,yz,zz from Voigt 1..6 -> 1,6,5,2,4,3
    EXPECT_EQ(s, (std::vector<double>{1. + 10 * k, 6, 5, 2, 4, 3}));
    EXPECT_EQ(read_doubles(f, g + "/von_mises", &dims)[0], 100.0 + k);
  }
  H5Fclose(f);

  const std::string x = slurp(dir / "fields.xdmf");
  EXPECT_NE(x.find("<Xdmf Version=\"3.0\">"), std::string::npos);
  EXPECT_NE(x.find("CollectionType=\"Temporal\""), std::string::npos);
  EXPECT_NE(x.find("fields.h5:/mesh/tets"), std::string::npos);
  EXPECT_NE(x.find("fields.h5:/steps/000002/stress"), std::string::npos);
  EXPECT_NE(x.find("AttributeType=\"Tensor6\""), std::string::npos);
  EXPECT_NE(x.find("<Time Value=\"1\"/>"), std::string::npos);
  EXPECT_EQ(x.find("/steps/000003"), std::string::npos);
  // Balanced tags: a cheap well-formedness check (no XML parser is a dependency).
  auto count = [&](const std::string& s) {
    size_t c = 0;
    for (size_t p = x.find(s); p != std::string::npos; p = x.find(s, p + 1)) ++c;
    return c;
  };
  EXPECT_EQ(count("<Grid "), count("</Grid>"));
  EXPECT_EQ(count("<DataItem "), count("</DataItem>"));
  EXPECT_EQ(count("<DataItem "), 3u * 7u);
  EXPECT_FALSE(fs::exists(dir / "fields.xdmf.tmp"));
  // Python's XML parser, when present, gives a real well-formedness check.
  if (std::system("python3 -c 'pass' >/dev/null 2>&1") == 0) {
    const std::string cmd =
        "python3 -c \"import xml.etree.ElementTree as E,sys; "
        "r=E.parse(sys.argv[1]).getroot(); "
        "assert len(r.findall('.//Time'))==3\" " +
        (dir / "fields.xdmf").string();
    EXPECT_EQ(std::system(cmd.c_str()), 0);
  }
  fs::remove_all(dir);
}

TEST(FieldWriter, WrongSizesAreRejected) {
  const fs::path dir = fresh_dir("sizes");
  TinyMesh mesh;
  FieldWriter w(dir, mesh.points, mesh.tets, mesh.body);
  std::vector<Vec3> short_pos(2);
  std::vector<std::array<double, 6>> stress(1);
  std::vector<double> vm(1);
  EXPECT_THROW(w.write(0, 0, short_pos, short_pos, stress, vm), std::logic_error);
  fs::remove_all(dir);
}

TEST(OutputDir, NotWritableIsAnInputErrorNamingTheFolder) {
  // A folder below a regular file cannot be created, even by root (permission bits would not
  // stop root, so they are no portable test).
  const fs::path base = fresh_dir("blocker");
  fs::create_directories(base);
  std::ofstream(base / "file") << "x";
  const fs::path dir = base / "file" / "out";
  TinyMesh mesh;
  try {
    FieldWriter w(dir, mesh.points, mesh.tets, mesh.body);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(ProbeWriter(dir, {"a"}), InputError);
  EXPECT_THROW(Json::object().write_file(dir / "summary.json"), InputError);
  fs::remove_all(base);
}

TEST(ProbeWriter, HeaderAndRows) {
  const fs::path dir = fresh_dir("probes");
  {
    ProbeWriter w(dir, {"tip", "c"});
    const std::vector<Vec3> v{{1, 2, 3}, {-4, 5.5, 0}};
    w.write(0.0, v, {1, 2, 3, 4});
    w.write(1e-3, v, {0.5, 0, 0, 0});
    // Flushed per row: readable before the writer closes.
    std::istringstream in(slurp(dir / "probes.csv"));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line,
              "time,tip_x,tip_y,tip_z,c_x,c_y,c_z,kinetic,strain,potential,dissipated,contact,"
              "contact_dissipated,total");
    std::getline(in, line);
    EXPECT_EQ(line,
              "0.0000000000e+00,1.0000000000e+00,2.0000000000e+00,3.0000000000e+00,"
              "-4.0000000000e+00,5.5000000000e+00,0.0000000000e+00,1.0000000000e+00,"
              "2.0000000000e+00,3.0000000000e+00,4.0000000000e+00,0.0000000000e+00,"
              "0.0000000000e+00,1.0000000000e+01");
    std::getline(in, line);
    EXPECT_EQ(line.substr(0, 16), "1.0000000000e-03");
    EXPECT_FALSE(std::getline(in, line));
    EXPECT_THROW(w.write(0, std::vector<Vec3>(1), {}), std::logic_error);
  }
  fs::remove_all(dir);
}

TEST(Json, EscapingAndLayout) {
  EXPECT_EQ(json_quote("a\"b\\c\n\t\x01/é"), "\"a\\\"b\\\\c\\n\\t\\u0001/é\"");
  Json j;
  j["name"] = "cantilever";
  j["steps"] = 123456789012345LL;
  j["ok"] = true;
  j["none"] = nullptr;
  j["list"].push_back(1);
  j["list"].push_back(2.5);
  j["nested"]["z"] = 1;
  j["nested"]["a"] = 2;   // insertion order kept, not sorted
  j["name"] = "renamed";  // existing key replaced in place
  EXPECT_EQ(j.dump(-1),
            "{\"name\":\"renamed\",\"steps\":123456789012345,\"ok\":true,\"none\":null,"
            "\"list\":[1,2.5],\"nested\":{\"z\":1,\"a\":2}}");
  EXPECT_EQ(Json::object().dump(), "{}");
  EXPECT_EQ(Json::array().dump(), "[]");
  EXPECT_EQ(Json(Json::Array{1, "x"}).dump(2), "[\n  1,\n  \"x\"\n]");
  EXPECT_THROW(Json(1)["x"], std::logic_error);
}

TEST(Json, DoublesRoundTripAndNonFiniteIsNull) {
  const double values[] = {0.1,
                           1.0 / 3.0,
                           -2.5e-300,
                           1e300,
                           6.02214076e23,
                           5e-324,
                           0.0,
                           -0.0,
                           1e21,
                           123456789.123456789,
                           std::numeric_limits<double>::max(),
                           std::nextafter(1.0, 2.0)};
  for (double v : values) {
    const std::string s = json_number(v);
    EXPECT_EQ(std::strtod(s.c_str(), nullptr), v) << s;
    EXPECT_EQ(s.find_first_not_of("0123456789+-.e"), std::string::npos) << s;
  }
  EXPECT_EQ(json_number(0.1), "0.1");
  EXPECT_EQ(json_number(std::nan("")), "null");
  EXPECT_EQ(json_number(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(Json(-std::numeric_limits<double>::infinity()).dump(), "null");
}

TEST(Json, WriteFileIsAtomic) {
  const fs::path dir = fresh_dir("json");
  fs::create_directories(dir);
  Json j;
  j["a"] = 1;
  j.write_file(dir / "summary.json");
  EXPECT_EQ(slurp(dir / "summary.json"), "{\n  \"a\": 1\n}\n");
  EXPECT_FALSE(fs::exists(dir / "summary.json.tmp"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace qdemsph
