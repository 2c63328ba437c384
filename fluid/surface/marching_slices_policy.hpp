#pragma once
// Custom field/vertex routines for marching slices (paper §2: "custom user-defined isosurface
// field and vertex calculation routines"; §7: tentacles textured by interpolating per-particle
// basis vectors and length coordinates onto the surface). Compile-time: the policy is a template
// argument, so there is no virtual call per corner or per particle.
//
// A policy is a copyable type with:
//   struct CornerData { ... };             // accumulated at each lattice corner; value-initialised
//   static constexpr bool kHasUser = true;  // false: no attributes (as without user data)
//   void add(CornerData& c, std::uint32_t particle, float weight) const;
//       // called for every particle influencing the corner, in a fixed order (particles sorted
//       // by (z, index)); `particle` is the input index, `weight` its field contribution f_i > 0
//   glm::vec4 vertex(const CornerData& a, const CornerData& b, float t) const;
//       // the vertex on the edge from corner a (t = 0) to corner b (t = 1); stored in
//       // SurfaceMesh::attributes
// The scalar field itself stays the paper's f (with per-particle strength and radius scale,
// which is how the paper modulates tentacle radius), so the exact particle cache and the
// closed-surface guarantees hold for every policy. Outputs stay thread-count invariant.
//
// Example: per-particle texture coordinates averaged by field weight.
//   struct UvPolicy {
//     struct CornerData { float u = 0, v = 0, w = 0; };
//     static constexpr bool kHasUser = true;
//     const glm::vec2* uv;
//     void add(CornerData& c, std::uint32_t i, float f) const { c.u += f * uv[i].x; c.v += f * uv[i].y; c.w += f; }
//     glm::vec4 vertex(const CornerData& a, const CornerData& b, float t) const { ... }
//   };
//   fluid::extractWithPolicy(extractor, input, params, UvPolicy{uvs.data()}, mesh);

#include "fluid/surface/detail/marching_slices_impl.hpp"
#include "fluid/surface/marching_slices.hpp"

namespace fluid {

// Like SurfaceExtractor::extract, with `policy` computing SurfaceMesh::attributes
// (SurfaceInput::user is ignored). Scratch for each policy type is kept in the extractor.
template <class Policy>
SurfaceStatus extractWithPolicy(SurfaceExtractor& extractor, const SurfaceInput& input, const SurfaceParams& params,
                                const Policy& policy, SurfaceMesh& out) {
  return detail::extractImpl(*extractor.state, input, params, policy, out);
}

}  // namespace fluid
