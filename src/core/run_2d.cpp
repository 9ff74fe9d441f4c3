// The 2D instantiations of every basis x mapping x scheme (run_impl.hpp).
#include "core/run_impl.hpp"

namespace mpm::run_detail {

template <>
RunResult run_dim<2>(Problem<2>& pb, const Config& cfg, const RunOptions& opt,
                     const BasisKind& basis, const MappingKind& mapping, const Scheme& scheme) {
  return visit_dim<2>(pb, cfg, opt, basis, mapping, scheme);
}

}  // namespace mpm::run_detail
