#include "mesh/gmsh_session.hpp"

#include <gmsh.h>

namespace qdemsph {
namespace {

std::recursive_mutex g_gmsh_mutex;
int g_gmsh_depth = 0;  // open sessions, guarded by g_gmsh_mutex

}  // namespace

GmshSession::GmshSession() : lock_(g_gmsh_mutex) {
  if (g_gmsh_depth == 0) {
    gmsh::initialize(0, nullptr, /*readConfigFiles=*/false);
    owner_ = true;
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.Verbosity", 0);
    // 2: errors throw an exception instead of aborting (the API default; set explicitly).
    gmsh::option::setNumber("General.AbortOnError", 2);
  }
  ++g_gmsh_depth;
}

GmshSession::~GmshSession() {
  --g_gmsh_depth;
  if (owner_) gmsh::finalize();
}

}  // namespace qdemsph
