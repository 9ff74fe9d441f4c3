#pragma once
// Every basis (for code that instantiates several, e.g. tests; the driver's generated units
// include only their own).
#include "basis/bspline.hpp"
#include "basis/cpdi.hpp"
#include "basis/ddmpm.hpp"
#include "basis/gimp.hpp"
#include "basis/linear.hpp"
#include "basis/maxent.hpp"
