#include "sph/fluid_setup.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "model/model.hpp"

namespace qdemsph {
namespace {

// Lattice counts along each axis for [lo, hi] with pitch dx (at least one).
std::array<int, 3> lattice(Vec3 lo, Vec3 hi, double dx) {
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a)
    n[a] = std::max(1, static_cast<int>(std::lround((hi[a] - lo[a]) / dx)));
  return n;
}

// Vertical axis: the one gravity points along (y when there is no gravity).
int up_axis(Vec3 g) {
  int a = 1;
  double best = 0;
  for (int k = 0; k < 3; ++k)
    if (std::fabs(g[k]) > best) best = std::fabs(g[k]), a = k;
  return a;
}

// Lattice point (i, j, k) of a box (cell centres at pitch dx from its min corner), turned by
// the box's rotation about that corner.
Vec3 box_point(const FluidBoxSpec& b, int i, int j, int k, double dx) {
  const Vec3 x{b.min.x + (i + 0.5) * dx, b.min.y + (j + 0.5) * dx, b.min.z + (k + 0.5) * dx};
  return b.rotate.none() ? x : b.rotate.apply(x, b.min);
}

// How far the ray from x (inside the box) along `up` (unit) runs before it leaves the box:
// the depth below the box's top that the hydrostatic start uses. An unrotated box under
// gravity along an axis: its top minus x (up = +axis) or x minus its bottom (up = -axis).
double depth_in_box(const FluidBoxSpec& b, Vec3 x, Vec3 up) {
  int axis = -1, nonzero = 0;
  for (int a = 0; a < 3; ++a)
    if (up[a] != 0) axis = a, ++nonzero;
  if (b.rotate.none() && nonzero == 1)
    return up[axis] > 0 ? b.max[axis] - x[axis] : x[axis] - b.min[axis];
  const RotationSpec back = b.rotate.inverse();
  const Vec3 q = back.apply(x, b.min) - b.min, u = back.apply(b.min + up, b.min) - b.min;
  double t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (u[a] > 0) t = std::min(t, (b.max[a] - b.min[a] - q[a]) / u[a]);
    if (u[a] < 0) t = std::min(t, -q[a] / u[a]);
  }
  return std::max(t, 0.0);
}

// The extent of a (turned) box along `up` (unit): top minus bottom of its 8 corners.
double box_height(const FluidBoxSpec& b, Vec3 up) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner{c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y,
                      c & 4 ? b.max.z : b.min.z};
    const double h = dot(b.rotate.apply(corner, b.min), up);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  return hi - lo;
}

}  // namespace

FluidSetup build_fluid(const FluidSpec& spec, Vec3 gravity) {
  FluidSetup f;
  const double dx = spec.spacing;
  f.dx = dx;
  const double gmag = norm(gravity);
  const int up = up_axis(gravity);
  const double up_sign = gravity[up] > 0 ? -1.0 : 1.0;  // +1: up is +axis
  Vec3 up_dir{0, 0, 0};  // against gravity (the up axis without gravity)
  if (gmag > 0)
    up_dir = gravity / -gmag;
  else
    up_dir[up] = 1.0;
  const double rho0 = spec.density;
  const double mass = rho0 * dx * dx * dx;

  for (const auto& b : spec.blocks) f.height = std::max(f.height, box_height(b, up_dir));
  double c0 = 0;
  if (spec.sound_speed) {
    c0 = *spec.sound_speed;
  } else {
    if (gmag == 0)
      throw InputError("fluid.sound_speed: 'auto' (10 sqrt(2 g H)) needs gravity; state it");
    c0 = 10.0 * std::sqrt(2.0 * gmag * f.height);
  }
  SphParams& P = f.params;
  P.kernel = WendlandC2::make(spec.smoothing * dx);
  P.eos = TaitEos::make(rho0, c0, spec.min_pressure);
  P.visc_type = spec.viscosity_type == "laminar" ? SphViscosity::Laminar : SphViscosity::Artificial;
  P.alpha = P.visc_type == SphViscosity::Artificial ? spec.viscosity : 0.0;
  P.nu = P.visc_type == SphViscosity::Laminar ? spec.viscosity : 0.0;
  P.delta = spec.delta;
  P.wall_viscosity = spec.wall_viscosity;
  P.gravity = gravity;
  if (spec.periodic_z) {
    if (up == 2)
      throw InputError(
          "fluid.periodic_z: gravity points along z; the periodic axis must be horizontal");
    f.z0 = (*spec.periodic_z)[0];
    f.period_z = (*spec.periodic_z)[1] - f.z0;
  }

  auto add = [&](Vec3 x, std::uint8_t type, double p) {
    f.x.push_back(x);
    f.v.push_back(Vec3{});
    f.p.push_back(p);
    // Fluid mass rho dx^3 with the initial (hydrostatic) density, so that m / rho = dx^3:
    // the lattice is then in equilibrium with the pressure gradient.
    const double rho = type == kSphFluid ? P.eos.density(p) : rho0;
    f.rho.push_back(rho);
    f.m.push_back(type == kSphFluid ? rho * dx * dx * dx : mass);
    f.type.push_back(type);
    f.gid.push_back(f.gid.size());
  };

  // Fluid blocks: lattice points at cell centres, hydrostatic pressure below each block's top
  // (along gravity: a turned block's depth runs to its face above the particle).
  for (std::size_t bi = 0; bi < spec.blocks.size(); ++bi) {
    const auto& b = spec.blocks[bi];
    const auto n = lattice(b.min, b.max, dx);
    const std::int64_t before = f.size();
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          const Vec3 x = box_point(b, i, j, k, dx);
          add(x, kSphFluid, spec.hydrostatic_init ? rho0 * gmag * depth_in_box(b, x, up_dir) : 0.0);
        }
    if (f.size() == before) throw InputError(fmt::format("fluid.blocks[{}]: no particle", bi));
  }
  f.n_fluid = f.size();

  // Tanks: lattice points of the inner box grown by L layers (not on the open top, nor across a
  // periodic z) that lie outside the inner box.
  for (const auto& t : spec.tanks) {
    const auto n = lattice(t.min, t.max, dx);
    const int L = t.thickness_layers;
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = -L;
      hi[a] = n[a] + L;
    }
    if (up_sign > 0)
      hi[up] = n[up];
    else
      lo[up] = 0;
    if (f.period_z > 0) {
      lo[2] = 0;
      hi[2] = n[2];
    }
    for (int k = lo[2]; k < hi[2]; ++k)
      for (int j = lo[1]; j < hi[1]; ++j)
        for (int i = lo[0]; i < hi[0]; ++i) {
          if (i >= 0 && i < n[0] && j >= 0 && j < n[1] && k >= 0 && k < n[2]) continue;
          add({t.min.x + (i + 0.5) * dx, t.min.y + (j + 0.5) * dx, t.min.z + (k + 0.5) * dx},
              kSphWall, 0.0);
        }
  }
  for (const auto& w : spec.walls) {
    const auto n = lattice(w.min, w.max, dx);
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) add(box_point(w, i, j, k, dx), kSphWall, 0.0);
  }
  f.n_wall = f.size() - f.n_fluid;

  f.lo = f.x[0];
  f.hi = f.x[0];
  for (const Vec3& x : f.x)
    for (int a = 0; a < 3; ++a) {
      f.lo[a] = std::min(f.lo[a], x[a]);
      f.hi[a] = std::max(f.hi[a], x[a]);
    }
  // Room for splashes above the highest particle; outside the box particles are clamped into
  // the border cells (exact, only slower).
  const double margin = 2.0 * P.kernel.support();
  for (int a = 0; a < 3; ++a) {
    f.lo[a] -= margin;
    f.hi[a] += margin;
  }
  f.hi[up] += up_sign > 0 ? f.height : 0.0;
  if (up_sign < 0) f.lo[up] -= f.height;
  return f;
}

void add_solid_markers(FluidSetup& f, const Model& model) {
  if (model.bodies.empty()) return;
  const double support = f.params.kernel.support();
  check_kernel_within_contact_cell(model, support, f.dx, f.params.kernel.h / f.dx);
  f.markers = build_solid_markers(model, f.dx, support);
  f.n_marker = f.markers.size();
  for (std::int64_t k = 0; k < f.n_marker; ++k) {
    const Vec3 x = f.markers.x[k];
    f.x.push_back(x);
    f.v.push_back(Vec3{});
    f.p.push_back(0.0);
    f.rho.push_back(f.params.eos.rho0);
    f.m.push_back(f.params.eos.rho0 * f.markers.volume[k]);
    f.type.push_back(kSphSolid);
    f.gid.push_back(f.gid.size());
    for (int a = 0; a < 3; ++a) {
      f.lo[a] = std::min(f.lo[a], x[a] - 2.0 * support);
      f.hi[a] = std::max(f.hi[a], x[a] + 2.0 * support);
    }
  }
}

std::string describe_fluid(const FluidSetup& f) {
  return fmt::format(
      "SPH ({} fluid + {} wall particles{}, dx = {:.4g} m, h = {:.4g} m, c0 = {:.4g} m/s)",
      f.n_fluid, f.n_wall,
      f.n_marker ? fmt::format(", coupled to the bodies by {} markers", f.n_marker) : "", f.dx,
      f.params.kernel.h, f.params.eos.c0);
}

}  // namespace qdemsph
