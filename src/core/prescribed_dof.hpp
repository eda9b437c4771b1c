#pragma once
// PrescribedDof: an essential condition on one degree of freedom of one node (or particle) - the
// prescribed displacement (or, in explicit runs, velocity) at load factor 1. pd and mpfem use it.
#include "core/types.hpp"

namespace lamina {

struct PrescribedDof {
  Index node = 0;             // node / particle index
  int component = 0;          // 0 = x, 1 = y, 2 = z
  Real value = 0.0;           // at ramp factor 1
  int ramp = -1;              // index into the problem's ramps (-1: linear in the load factor / constant)
  bool velocity = false;      // explicit: prescribed velocity instead of displacement
};

}  // namespace lamina
