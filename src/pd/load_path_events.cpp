#include "pd/load_path_events.hpp"

#include <cmath>

namespace lamina::pd {

std::vector<StiffnessChange> detect_stiffness_changes(const std::vector<Real>& load, const std::vector<Real>& displacement,
                                                      Real min_drop) {
  std::vector<StiffnessChange> events;
  const std::size_t points = std::min(load.size(), displacement.size());
  if (points < 4) return events;
  // Tangent stiffness per increment (n = 1 .. points-1), at mid-increment load.
  const std::size_t m = points - 1;
  std::vector<Real> k(m), mid(m);
  for (std::size_t n = 0; n < m; ++n) {
    const Real dp = load[n + 1] - load[n], dd = displacement[n + 1] - displacement[n];
    k[n] = dd != 0 ? dp / dd : INFINITY;
    mid[n] = 0.5 * (load[n] + load[n + 1]);
  }
  // Relative drop rate between consecutive increments (q[n] between k[n-1] and k[n]).
  std::vector<Real> q(m, 0.0);
  for (std::size_t n = 1; n < m; ++n) {
    const bool positive = k[n - 1] > 0 && k[n] > 0 && std::isfinite(k[n - 1]) && std::isfinite(k[n]);
    const Real dl = mid[n] - mid[n - 1];
    if (dl <= 0) continue;
    // a negative or vanishing tangent (snap) counts as a full drop over this increment
    q[n] = positive ? std::log(k[n - 1] / k[n]) / dl : std::log(1e3) / dl;
  }
  const Real k0 = k[0];
  if (!(k0 > 0) || !std::isfinite(k0)) return events;
  std::size_t last_end = 0;
  for (std::size_t n = 1; n < m; ++n) {
    if (q[n] <= 0 || n <= last_end) continue;
    const bool peak = q[n] >= q[n - 1] && (n + 1 >= m || q[n] > q[n + 1]);
    if (!peak) continue;
    // prominence: the peak must at least double the slowest rate since the previous event
    Real trough = q[n];
    for (std::size_t j = last_end + 1; j < n; ++j) trough = std::min(trough, q[j]);
    if (q[n] < 2.0 * std::max(trough, 0.0)) continue;
    // extent: back to half the peak on either side
    std::size_t a = n, b = n;
    while (a > last_end + 1 && q[a - 1] > 0.5 * q[n]) --a;
    while (b + 1 < m && q[b + 1] > 0.5 * q[n] && q[b + 1] <= q[b]) ++b;  // ... or to the trough before a new rise
    // tangents: increment a-1 (before the drop) and increment b (after it)
    const std::size_t before = a - 1, after = b;
    const Real kb = k[before], ka = k[after];
    const Real drop = (ka > 0 && std::isfinite(ka)) ? 1.0 - ka / kb : 1.0;
    if (drop < min_drop) continue;
    // line 1 through the end of increment `before`, slope kb; line 2 through the end of `after`, slope ka
    const Real d1 = displacement[before + 1], p1 = load[before + 1];
    const Real d2 = displacement[after + 1], p2 = load[after + 1];
    // settled stiffness: past a recovery right after the drop (snap), then down the decaying tail of q
    std::size_t settled = b;
    while (settled + 1 < m && q[settled + 1] < 0) ++settled;
    while (settled + 1 < m && q[settled + 1] > 0.1 * q[n] && q[settled + 1] <= q[settled]) ++settled;
    StiffnessChange e;
    e.peak_load = mid[n];
    e.stiffness_ratio = k[settled] / k0;
    if (std::isfinite(kb) && std::isfinite(ka) && std::abs(kb - ka) > 1e-12 * std::abs(kb)) {
      e.displacement = (p2 - p1 + kb * d1 - ka * d2) / (kb - ka);
      e.load = p1 + kb * (e.displacement - d1);
    } else {
      e.displacement = d1;
      e.load = p1;
    }
    // keep the intersection inside the event's own load range
    if (!(e.load >= load[before] && e.load <= load[after + 1])) {
      e.load = mid[n];
      e.displacement = 0.5 * (displacement[n] + displacement[n + 1]);
    }
    events.push_back(e);
    last_end = settled;
  }
  return events;
}

}  // namespace lamina::pd
