// The mapping concept (mapping/mapping.hpp) checked for every mapping with the P1 basis, here
// rather than in the mapping headers so that those do not depend on a basis; the steppers
// (driver/stepper_impl.hpp) check every basis x mapping they instantiate.
#include "mapping/mapping.hpp"

#include "basis/linear.hpp"
#include "mapping/cubic_spline.hpp"
#include "mapping/direct.hpp"
#include "mapping/mls.hpp"
#include "mapping/tls.hpp"

namespace mpm {

static_assert(MappingFor<DirectMapping, Simulation<1, LinearBasis<1>, DirectMapping>> &&
              MappingFor<DirectMapping, Simulation<2, LinearBasis<2>, DirectMapping>>);
static_assert(MappingFor<CubicSplineMapping, Simulation<1, LinearBasis<1>, CubicSplineMapping>>);
static_assert(MappingFor<TlsMapping, Simulation<1, LinearBasis<1>, TlsMapping>> &&
              MappingFor<TlsMapping, Simulation<2, LinearBasis<2>, TlsMapping>>);
// The steppers run MLS and IMLS as MlsFamilyMapping (stepped_mapping_t); the tests run each.
static_assert(MappingFor<MlsFamilyMapping, Simulation<1, LinearBasis<1>, MlsFamilyMapping>> &&
              MappingFor<MlsFamilyMapping, Simulation<2, LinearBasis<2>, MlsFamilyMapping>>);
static_assert(MappingFor<MlsMapping, Simulation<1, LinearBasis<1>, MlsMapping>> &&
              MappingFor<MlsMapping, Simulation<2, LinearBasis<2>, MlsMapping>>);
static_assert(MappingFor<ImlsMapping, Simulation<1, LinearBasis<1>, ImlsMapping>> &&
              MappingFor<ImlsMapping, Simulation<2, LinearBasis<2>, ImlsMapping>>);

}  // namespace mpm
