#pragma once
// The weights w_I(x) of an evaluation point's neighbours and their first and second derivatives with
// respect to x (seed 004 eqs 1-6..1-10), for box and spherical supports, over flat arrays of the
// neighbours' offsets x - x_I and inverse radii. Internal to src/mls (the MLS kernel's first step).
#include <cmath>
#include <cstddef>

#include "core/types.hpp"
#include "mls/real4.hpp"
#include "mls/weight_function.hpp"

namespace lamina::mls::detail {

using simd::load4;
using simd::Real4;
using simd::store4;

/// Box supports: per direction d the factors w(s_d), w'(s_d) sign(dx_d) / R_d, w''(s_d) / R_d^2 into
/// `factors` (9 rows of n), then their products (in 3D without second derivatives four at a time:
/// GCC does not vectorise that loop itself).
template <int Dim, Weight Kind, bool Second>
void compute_box_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets, const Real* inverse_radii,
                         Real* factors, Real* weights) {
  for (int d = 0; d < Dim; ++d) {
    const Real* offset = offsets + d * stride;
    const Real* inverse = inverse_radii + d * stride;
    Real* value = factors + (3 * d) * n;
    Real* first = factors + (3 * d + 1) * n;
    Real* second = factors + (3 * d + 2) * n;
    for (std::size_t j = 0; j < n; ++j) {
      const WeightValue w = function.template evaluate_inside<Kind>(std::abs(offset[j]) * inverse[j]);
      value[j] = w.value;
      first[j] = std::copysign(w.first, -offset[j]) * inverse[j];  // sign(dx_d) w' / R_d, w' <= 0
      if constexpr (Second) second[j] = w.second * inverse[j] * inverse[j];
    }
  }
  auto row = [&](int d, int q) { return factors + (3 * d + q) * n; };  // q: 0 value, 1 first, 2 second
  if constexpr (Dim == 1) {
    for (std::size_t j = 0; j < n; ++j) {
      weights[j] = row(0, 0)[j];
      weights[n + j] = row(0, 1)[j];
      if constexpr (Second) weights[4 * n + j] = row(0, 2)[j];
    }
  } else if constexpr (Dim == 2) {
    const Real *v0 = row(0, 0), *v1 = row(1, 0), *f0 = row(0, 1), *f1 = row(1, 1), *s0 = row(0, 2), *s1 = row(1, 2);
    for (std::size_t j = 0; j < n; ++j) {
      weights[j] = v0[j] * v1[j];
      weights[n + j] = f0[j] * v1[j];
      weights[2 * n + j] = v0[j] * f1[j];
      if constexpr (Second) {
        weights[4 * n + j] = s0[j] * v1[j];
        weights[5 * n + j] = v0[j] * s1[j];
        weights[7 * n + j] = f0[j] * f1[j];
      }
    }
  } else {
    const Real *v0 = row(0, 0), *v1 = row(1, 0), *v2 = row(2, 0);
    const Real *f0 = row(0, 1), *f1 = row(1, 1), *f2 = row(2, 1);
    const Real *s0 = row(0, 2), *s1 = row(1, 2), *s2 = row(2, 2);
    std::size_t j = 0;
    if constexpr (!Second)
      for (; j + 4 <= n; j += 4) {  // four at a time (the factor rows and the weights do not overlap)
        const Real4 a = load4(v0 + j), b = load4(v1 + j), c = load4(v2 + j);
        const Real4 ab = a * b;  // the same products, in the same order, as the loop below
        store4(weights + j, ab * c, 4);
        store4(weights + n + j, load4(f0 + j) * b * c, 4);
        store4(weights + 2 * n + j, a * load4(f1 + j) * c, 4);
        store4(weights + 3 * n + j, ab * load4(f2 + j), 4);
      }
    for (; j < n; ++j) {
      weights[j] = v0[j] * v1[j] * v2[j];
      weights[n + j] = f0[j] * v1[j] * v2[j];
      weights[2 * n + j] = v0[j] * f1[j] * v2[j];
      weights[3 * n + j] = v0[j] * v1[j] * f2[j];
      if constexpr (Second) {
        weights[4 * n + j] = s0[j] * v1[j] * v2[j];
        weights[5 * n + j] = v0[j] * s1[j] * v2[j];
        weights[6 * n + j] = v0[j] * v1[j] * s2[j];
        weights[7 * n + j] = f0[j] * f1[j] * v2[j];
        weights[8 * n + j] = v0[j] * f1[j] * f2[j];
        weights[9 * n + j] = f0[j] * v1[j] * f2[j];
      }
    }
  }
}

/// Spherical supports (see compute_weights).
template <int Dim, Weight Kind, bool Second>
void compute_sphere_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets,
                            const Real* inverse_radii, Real* weights) {
  for (std::size_t j = 0; j < n; ++j) {
    // u_d = dx_d / R_d (R_d equal on every axis for a sphere, unequal for an ellipsoid), s = |u|
    Real scaled[3], inverse[3];
    for (int d = 0; d < Dim; ++d) {
      inverse[d] = inverse_radii[d * stride + j];
      scaled[d] = offsets[d * stride + j] * inverse[d];
    }
    Real squared = 0.0;
    for (int d = 0; d < Dim; ++d) squared += scaled[d] * scaled[d];
    const Real s = std::sqrt(squared);
    const WeightValue w = function.template evaluate_inside<Kind>(s);
    weights[j] = w.value;
    // ds/dx_d = u_d / (s R_d): w_,d = (w'/s) u_d / R_d
    Real gradient[3];
    for (int d = 0; d < Dim; ++d) {
      gradient[d] = scaled[d] * inverse[d];
      weights[(1 + d) * n + j] = w.first_over_s * gradient[d];
    }
    if constexpr (Second) {
      // w_,ab = (w'' - w'/s) (u_a / R_a)(u_b / R_b) / s^2 + (w'/s) delta_ab / R_a^2
      const Real radial = s > 0.0 ? (w.second - w.first_over_s) / squared : 0.0;
      constexpr int first_index[6] = {0, 1, 2, 0, 1, 2};
      constexpr int second_index[6] = {0, 1, 2, 1, 2, 0};
      for (int k = 0; k < 6; ++k) {
        const int a = first_index[k], b = second_index[k];
        if (a >= Dim || b >= Dim) continue;
        weights[(4 + k) * n + j] =
            radial * gradient[a] * gradient[b] + (a == b ? w.first_over_s * inverse[a] * inverse[a] : 0.0);
      }
    }
  }
}

/// Weights of all n neighbours and their derivatives with respect to the evaluation point x, written to
/// weights[q * n + j] for q = 0 (w), 1..3 (w_,i), 4..9 (w_,ij in xx yy zz xy yz zx; only if Second).
/// Box: w = prod_d w(s_d), s_d = |dx_d| / R_d. Sphere: s = |dx| / R, w_,i = (w'/s) dx_i / R^2,
/// w_,ij = (w'/s) delta_ij / R^2 + (w'' - w'/s) (dx_i / r)(dx_j / r) / R^2.
/// offsets, inverse_radii: 3 rows of n at `stride` (structure of arrays); factors: 9 n scratch values.
template <int Dim, bool Box, Weight Kind, bool Second>
void compute_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets, const Real* inverse_radii,
                     Real* factors, Real* weights) {
  if constexpr (Box) compute_box_weights<Dim, Kind, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
  else compute_sphere_weights<Dim, Kind, Second>(function, n, stride, offsets, inverse_radii, weights);
}

template <int Dim, bool Box, bool Second>
void compute_weights(const WeightFunction& function, std::size_t n, std::size_t stride, const Real* offsets, const Real* inverse_radii,
                     Real* factors, Real* weights) {
  switch (function.kind()) {
    case Weight::gauss:
      return compute_weights<Dim, Box, Weight::gauss, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
    case Weight::cubic_spline:
      return compute_weights<Dim, Box, Weight::cubic_spline, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
    case Weight::quartic_spline:
      return compute_weights<Dim, Box, Weight::quartic_spline, Second>(function, n, stride, offsets, inverse_radii, factors, weights);
  }
}

template <int Dim>
void compute_weights(const WeightFunction& function, bool box, bool second, std::size_t n, std::size_t stride, const Real* offsets,
                     const Real* inverse_radii, Real* factors, Real* weights) {
  if (box) {
    if (second) compute_weights<Dim, true, true>(function, n, stride, offsets, inverse_radii, factors, weights);
    else compute_weights<Dim, true, false>(function, n, stride, offsets, inverse_radii, factors, weights);
  } else {
    if (second) compute_weights<Dim, false, true>(function, n, stride, offsets, inverse_radii, factors, weights);
    else compute_weights<Dim, false, false>(function, n, stride, offsets, inverse_radii, factors, weights);
  }
}

}  // namespace lamina::mls::detail
