// GmshSession: the guard every use of the gmsh library goes through (mesh generation: shogi
// pieces, tests that compare with libgmsh). Reading .msh files needs no gmsh
// (mesh/msh_reader.hpp).
#pragma once

#include <mutex>

namespace qdemsph {

// Serialises use of the (global, not thread-safe) gmsh library and initialises it on demand:
// the outermost session initialises gmsh (no config files, terminal output off, errors thrown
// as exceptions) and finalises it on destruction. Nested sessions on the same thread reuse it.
class GmshSession {
 public:
  GmshSession();
  ~GmshSession();
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

 private:
  std::unique_lock<std::recursive_mutex> lock_;
  bool owner_ = false;
};

}  // namespace qdemsph
