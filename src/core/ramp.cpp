#include "core/ramp.hpp"

#include <algorithm>

namespace lamina {

Real Ramp::factor(Real s, Real end) const {
  switch (kind) {
    case Kind::linear: return end > 0 ? std::clamp(s / end, 0.0, 1.0) : 1.0;
    case Kind::step: return 1.0;
    case Kind::table: {
      if (table.empty()) return 1.0;
      if (s <= table.front()[0]) return table.front()[1];
      for (std::size_t i = 1; i < table.size(); ++i)
        if (s <= table[i][0]) {
          const Real u = (s - table[i - 1][0]) / (table[i][0] - table[i - 1][0]);
          return table[i - 1][1] + u * (table[i][1] - table[i - 1][1]);
        }
      return table.back()[1];
    }
  }
  return 1.0;
}

}  // namespace lamina
