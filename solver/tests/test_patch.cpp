// MacNeal-Harder (1985) patch test (BENCHMARKS.md section 2): a unit cube of 7 distorted
// hexes, each split into 12 tets; boundary corners carry the linear displacement field,
// interior nodes are found by the static solver. Linear tets reproduce the field and the
// constant stress (2000, 2000, 2000, 400, 400, 400) to round-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "integrate/stepper.hpp"
#include "mesh/gmsh_io.hpp"
#include "physics/element.hpp"
#include "scene_fixture.hpp"

namespace qdemsph {
namespace {

Vec3 exact_u(Vec3 p) {
  return 1e-3 *
         Vec3{(2 * p.x + p.y + p.z) / 2, (p.x + 2 * p.y + p.z) / 2, (p.x + p.y + 2 * p.z) / 2};
}

// Splits the hex (quad a, quad b, a_i joined to b_i) into 12 tets around a new centre
// vertex; each face is cut along the diagonal through its smallest vertex index, a choice
// made from the face alone, so neighbouring hexes conform.
void add_hex(TetMesh& m, std::array<int, 4> a, std::array<int, 4> b) {
  Vec3 c{0, 0, 0};
  for (int i = 0; i < 4; ++i) c += 0.125 * (m.points[a[i]] + m.points[b[i]]);
  const int ci = static_cast<int>(m.points.size());
  m.points.push_back(c);
  std::vector<std::array<int, 4>> faces = {a, b};
  for (int i = 0; i < 4; ++i) faces.push_back({a[i], a[(i + 1) % 4], b[(i + 1) % 4], b[i]});
  for (auto f : faces) {
    const int k = static_cast<int>(std::min_element(f.begin(), f.end()) - f.begin());
    const int p0 = f[k], p1 = f[(k + 1) % 4], p2 = f[(k + 2) % 4], p3 = f[(k + 3) % 4];
    for (auto tri : {std::array<int, 3>{p0, p1, p2}, std::array<int, 3>{p0, p2, p3}}) {
      std::array<int32_t, 4> t{tri[0], tri[1], tri[2], ci};
      const Vec3 p[4] = {m.points[t[0]], m.points[t[1]], m.points[t[2]], m.points[t[3]]};
      if (det(edge_matrix(p)) < 0) std::swap(t[0], t[1]);
      m.tets.push_back(t);
    }
  }
}

TetMesh patch_mesh() {
  TetMesh m;
  for (int k = 0; k < 2; ++k)  // outer corners o0..o7: bottom ring then top ring
    for (auto [x, y] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}})
      m.points.push_back({double(x), double(y), double(k)});
  const Vec3 inner[8] = {{0.249, 0.342, 0.192}, {0.826, 0.288, 0.288}, {0.850, 0.649, 0.263},
                         {0.273, 0.750, 0.230}, {0.320, 0.186, 0.643}, {0.677, 0.305, 0.683},
                         {0.788, 0.693, 0.644}, {0.165, 0.745, 0.702}};
  for (auto p : inner) m.points.push_back(p);
  auto o = [](int i) { return i; };
  auto in = [](int i) { return 8 + i; };
  add_hex(m, {in(0), in(1), in(2), in(3)}, {in(4), in(5), in(6), in(7)});
  add_hex(m, {o(0), o(1), o(2), o(3)}, {in(0), in(1), in(2), in(3)});
  add_hex(m, {in(4), in(5), in(6), in(7)}, {o(4), o(5), o(6), o(7)});
  add_hex(m, {o(0), o(1), o(5), o(4)}, {in(0), in(1), in(5), in(4)});
  add_hex(m, {in(3), in(2), in(6), in(7)}, {o(3), o(2), o(6), o(7)});
  add_hex(m, {in(0), in(3), in(7), in(4)}, {o(0), o(3), o(7), o(4)});
  add_hex(m, {o(1), o(2), o(6), o(5)}, {in(1), in(2), in(6), in(5)});
  return m;
}

TEST(PatchTest, LinearTetsReproduceConstantStrain) {
  const auto dir = testing::scratch_dir("patch");
  const TetMesh mesh = patch_mesh();
  ASSERT_EQ(mesh.tets.size(), 84u);
  write_gmsh(dir / "patch.msh", mesh);
  std::string yaml = R"(
run: {mode: static, end_time: 1.0}
materials: {m: {law: linear, E: 1.0e6, nu: 0.25, density: 1000}}
bodies: [{name: cube, material: m, mesh: {type: gmsh, file: patch.msh}}]
constraints:
)";
  for (int i = 0; i < 8; ++i) {
    const Vec3 p = mesh.points[i];
    auto r = [](double c) {
      return "[" + std::to_string(c - 1e-9) + ", " + std::to_string(c + 1e-9) + "]";
    };
    yaml += "  - {type: fixed, body: cube, region: {x: " + r(p.x) + ", y: " + r(p.y) +
            ", z: " + r(p.z) + "}}\n";
  }
  testing::Problem pb = testing::make_problem(yaml, dir / "patch.yaml");
  Model& model = pb.model;
  for (int i = 0; i < 8; ++i) model.x[i] = model.X[i] + exact_u(model.X[i]);
  pb.backend->upload(model);
  Stepper st(model, *pb.backend, 0.5 * model.dt_critical);
  const RelaxResult r = st.relax(1e-11, 2000000, false);
  EXPECT_TRUE(r.converged) << "residual " << r.residual << " after " << r.iterations;
  std::printf("patch: %ld iterations, residual %g\n", (long)r.iterations, r.residual);

  const HostFields h = pb.backend->download(true);
  double err = 0;
  for (std::size_t i = 0; i < h.x.size(); ++i)
    err = std::max(err, norm(h.x[i] - model.X[i] - exact_u(model.X[i])));
  EXPECT_LT(err / 1e-3, 1e-9) << "max nodal displacement error " << err;
  const double expect[6] = {2000, 2000, 2000, 400, 400, 400};
  double serr = 0;
  for (const auto& s : h.stress)
    for (int c = 0; c < 6; ++c) serr = std::max(serr, std::abs(s[c] - expect[c]));
  EXPECT_LT(serr / 2000, 1e-8) << "max stress error " << serr << " Pa";
}

// Held components (`fixed` with `components`): a block with roller supports on three
// symmetry planes (x = 0 holds x, y = 0 holds y, z = 0 holds z) under a uniform traction -p
// on its top is in uniaxial stress, the exact solution sigma_zz = -p, u = (nu p x / E,
// nu p y / E, -p z / E): linear in x, so the tets reproduce it to the solver's tolerance, and
// the rollers let the block spread sideways (a clamped base would not).
TEST(PatchTest, SymmetryPlanesHoldOneComponentEach) {
  const double E = 1.0e6, nu = 0.25, p = 1000, H = 2.0;  // as in the scene
  testing::Problem pb = testing::make_problem(R"(
run: {mode: static, end_time: 1.0}
materials: {m: {law: linear, E: 1.0e6, nu: 0.25, density: 1000}}
bodies: [{name: block, material: m, mesh: {type: box, size: [1.0, 0.5, 2.0], cells: [2, 2, 4]}}]
constraints:
  - {type: fixed, body: block, region: {x: [0, 0]}, components: [x]}
  - {type: fixed, body: block, region: {y: [0, 0]}, components: [y]}
  - {type: fixed, body: block, region: {z: [0, 0]}, components: [z]}
loads:
  - {type: traction, body: block, region: {z: [2, 2]}, traction: [0, 0, -1000]}
)");
  Model& model = pb.model;
  Stepper st(model, *pb.backend, 0.5 * model.dt_critical);
  const RelaxResult r = st.relax(1e-11, 2000000, false);
  EXPECT_TRUE(r.converged) << "residual " << r.residual << " after " << r.iterations;
  const HostFields h = pb.backend->download(true);
  double err = 0;
  for (std::size_t i = 0; i < h.x.size(); ++i) {
    const Vec3 X = model.X[i];
    const Vec3 u{nu * p * X.x / E, nu * p * X.y / E, -p * X.z / E};
    err = std::max(err, norm(h.x[i] - X - u));
  }
  const double scale = p * H / E;
  std::printf("rollers: %ld iterations, max |u - exact| / (p H / E) = %.2e, top corner x %.6e m\n",
              (long)r.iterations, err / scale, h.x.back().x);
  EXPECT_LT(err / scale, 1e-8);
  double serr = 0;  // stress order xx, yy, zz, yz, xz, xy
  for (const auto& s : h.stress)
    for (int c = 0; c < 6; ++c) serr = std::max(serr, std::abs(s[c] - (c == 2 ? -p : 0.0)));
  EXPECT_LT(serr / p, 1e-7) << "max stress error " << serr << " Pa";
}

// The same block released dynamically with a pull along (1, 1, 1) on its top: the held
// components of the roller vertices stay exactly at their reference values while the free
// ones move.
TEST(PatchTest, HeldComponentsStayPutInDynamics) {
  testing::Problem pb = testing::make_problem(R"(
run: {end_time: 1.0}
materials: {m: {law: svk, E: 1.0e6, nu: 0.25, density: 1000, viscosity: 10}}
bodies: [{name: block, material: m, mesh: {type: box, size: [1.0, 0.5, 2.0], cells: [2, 2, 4]}}]
constraints:
  - {type: fixed, body: block, region: {x: [0, 0]}, components: [x]}
  - {type: fixed, body: block, region: {z: [0, 0]}, components: [z, y]}
loads:
  - {type: traction, body: block, region: {z: [2, 2]}, traction: [1000, 1000, 1000]}
)");
  Model& model = pb.model;
  Stepper st(model, *pb.backend, 0.5 * model.dt_critical);
  for (int n = 0; n < 300; ++n) st.step();
  const HostFields h = pb.backend->download(false);
  double held = 0, moved = 0;
  for (std::size_t i = 0; i < h.x.size(); ++i) {
    const Vec3 X = model.X[i], d = h.x[i] - X;
    const bool hx = X.x == 0, hz = X.z == 0;
    held = std::max(
        {held, hx ? std::abs(d.x) : 0.0, hz ? std::max(std::abs(d.y), std::abs(d.z)) : 0.0});
    moved = std::max(moved, norm(d));
  }
  EXPECT_EQ(held, 0.0);
  EXPECT_GT(moved, 1e-5);
}

}  // namespace
}  // namespace qdemsph
