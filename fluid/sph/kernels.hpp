#pragma once
// SPH smoothing kernels for fluid/sph.
//
// Cubic spline (Monaghan 1992, "Smoothed particle hydrodynamics", eq. 2.6, written with the
// support radius H instead of the smoothing length h = H/2, as in Bender & Koschier 2015 and
// SPlisHSPlasH): with q = r/H and sigma = 8/(pi H^3),
//   W(q) = sigma (6q^3 - 6q^2 + 1)   for 0 <= q <= 1/2
//   W(q) = sigma 2(1 - q)^3           for 1/2 < q <= 1
//   W(q) = 0                          otherwise.
// Integrates to 1 over R^3; grad W(x) = W'(r) x/r is odd (grad W(-x) = -grad W(x)), which makes
// the symmetric pressure forces of Becker & Teschner 2007 eq. 6 conserve momentum.

#include <glm/glm.hpp>

#include <cmath>

namespace fluid {

struct CubicSplineKernel {
  float support = 0.1f;  // H (m), > 0
  float inv_support = 10.0f;
  float sigma = 0.0f;  // 8 / (pi H^3)

  static CubicSplineKernel make(float support_radius) {
    CubicSplineKernel k;
    k.support = support_radius;
    k.inv_support = 1.0f / support_radius;
    k.sigma = 8.0f / (3.14159265358979f * support_radius * support_radius * support_radius);
    return k;
  }

  // W(r), r = |x| >= 0, units 1/m^3.
  float value(float r) const {
    const float q = r * inv_support;
    if (q > 1.0f) return 0.0f;
    if (q <= 0.5f) return sigma * (6.0f * q * q * q - 6.0f * q * q + 1.0f);
    const float t = 1.0f - q;
    return sigma * 2.0f * t * t * t;
  }

  // dW/dr (units 1/m^4), <= 0 for all r.
  float derivative(float r) const {
    const float q = r * inv_support;
    if (q > 1.0f) return 0.0f;
    if (q <= 0.5f) return sigma * inv_support * (18.0f * q * q - 12.0f * q);
    const float t = 1.0f - q;
    return -sigma * inv_support * 6.0f * t * t;
  }

  // W(r) and W'(r) / r in one evaluation (one branch, the same expressions as value() and
  // derivative()), for 0 < r <= H: the caller has already tested the support.
  void evaluateInside(float r, float& w, float& derivative_over_r) const {
    const float q = r * inv_support;
    float dw;
    if (q <= 0.5f) {
      w = sigma * (6.0f * q * q * q - 6.0f * q * q + 1.0f);
      dw = sigma * inv_support * (18.0f * q * q - 12.0f * q);
    } else {
      const float t = 1.0f - q;
      w = sigma * 2.0f * t * t * t;
      dw = -sigma * inv_support * 6.0f * t * t;
    }
    derivative_over_r = dw / r;
  }

  // grad_x W(|x|) for x = x_i - x_j; zero at x = 0 (the kernel's gradient is continuous there).
  glm::vec3 gradient(glm::vec3 x, float r) const {
    if (r <= 1e-9f * support || r > support) return glm::vec3(0.0f);
    return (derivative(r) / r) * x;
  }
  glm::vec3 gradient(glm::vec3 x) const { return gradient(x, glm::length(x)); }
};

}  // namespace fluid
