#include "core/error.hpp"
#include "core/exec_host.hpp"
#include "integrate/qdem_backend.hpp"

namespace qdemsph {

SolidViews Backend::solid_views() {
  throw InputError("backend '" + name() + "' cannot couple bodies to a fluid");
}

std::unique_ptr<Backend> make_host_backend() {
  return std::make_unique<QdemBackend<HostExec>>("cpu");
}

#ifndef QDEMSPH_HAVE_CUDA
std::unique_ptr<Backend> make_cuda_backend() {
  throw InputError("backend 'cuda' is not available: this qdemsph was built without CUDA");
}
#endif

std::unique_ptr<Backend> make_backend(const std::string& name) {
  if (name == "cpu") return make_host_backend();
  if (name == "cuda") return make_cuda_backend();
  throw InputError("unknown backend '" + name + "' (allowed: cpu, cuda)");
}

}  // namespace qdemsph
