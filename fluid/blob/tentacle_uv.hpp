#pragma once
// Tentacle texturing as the paper does it (Rosenberg & Birdwell 2008 §7): "cylindrically textured by
// interpolating per particle basis vectors and length coordinates onto the surface using a custom
// field calculation routine", then u, v from "a custom vertex calculation routine".
//
// BlobTentaclePolicy is the marching-slices policy (fluid/surface/marching_slices_policy.hpp): at
// each lattice corner it accumulates the field-weighted length coordinate of the tentacle particles
// and their share of the field; the vertex routine interpolates both along the edge and writes
//   attributes = (u, v, tentacle, 0): v = length coordinate (0 base .. 1 tip), tentacle = the
//   tentacles' share of the field at the vertex (1 on a tentacle, 0 on the core), u = 0 here.
// u (the angle around the tentacle) needs the vertex position relative to the interpolated axis,
// and the policy interface hands vertex() only the two corners' accumulated data and t, not the
// corner or vertex positions, so u cannot be computed inside it. blobTentacleU fills it in a pass
// over the finished mesh from each vertex's position and the basis vectors of its nearest tentacle
// particle. (A vertex(a, b, t, position) overload in the policy interface would remove that pass.)

#include "fluid/blob/blob.hpp"
#include "fluid/surface/marching_slices.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace fluid {

struct BlobTentaclePolicy {
  struct CornerData {
    float field = 0.0f;     // sum of f_i
    float tentacle = 0.0f;  // sum of f_i over tentacle particles
    float length = 0.0f;    // sum of f_i s_i over tentacle particles
  };
  static constexpr bool kHasUser = true;
  const float* length_coord = nullptr;  // BlobParticles::length_coord (-1 = core)

  void add(CornerData& c, std::uint32_t particle, float weight) const {
    c.field += weight;
    const float s = length_coord[particle];
    if (s >= 0.0f) {
      c.tentacle += weight;
      c.length += weight * s;
    }
  }
  glm::vec4 vertex(const CornerData& a, const CornerData& b, float t) const {
    const float field = a.field + t * (b.field - a.field);
    const float tentacle = a.tentacle + t * (b.tentacle - a.tentacle);
    const float length = a.length + t * (b.length - a.length);
    return {0.0f, tentacle > 0.0f ? length / tentacle : 0.0f, field > 0.0f ? tentacle / field : 0.0f, 0.0f};
  }
};

// Fills attributes[k].x = u in [0, 1) for every vertex with attributes[k].z >= min_share: the angle
// of (vertex - nearest tentacle particle) around that particle's tangent, measured from its normal
// (BlobParticles::tangent / normal). `origin` is SurfaceParams::origin (mesh positions are p - origin).
void blobTentacleU(SurfaceMesh& mesh, const BlobWorld& world, glm::vec3 origin = glm::vec3(0.0f),
                   float min_share = 0.05f);
// The same from the parts of the world it reads (a copy of them, for meshing on another thread):
// the particles, the tentacles' particle chains (BlobTarget::tentacle_particles) and the spacing.
void blobTentacleU(SurfaceMesh& mesh, const BlobParticles& particles,
                   std::span<const std::vector<std::uint32_t>> tentacles, float spacing,
                   glm::vec3 origin = glm::vec3(0.0f), float min_share = 0.05f);

}  // namespace fluid
