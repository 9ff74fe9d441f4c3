// The 1D instantiations of every basis x mapping x scheme (run_impl.hpp).
#include "core/run_impl.hpp"

namespace mpm::run_detail {

template <>
RunResult run_dim<1>(Problem<1>& pb, const Config& cfg, const RunOptions& opt,
                     const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme) {
  return visit_dim<1>(pb, cfg, opt, basis, mapping, scheme);
}

}  // namespace mpm::run_detail
