#pragma once
// Bit-for-bit comparison of surface meshes, for the tests that check a mesh made another way
// (asynchronously, on a worker) is exactly the synchronous extractor's.

#include "fluid/surface/marching_slices.hpp"

#include <cstring>
#include <string>
#include <vector>

namespace test_support {

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// The first of the mesh's arrays whose bits differ ("positions differ", ...), empty when none does.
inline std::string meshBitsDiffer(const fluid::SurfaceMesh& got, const fluid::SurfaceMesh& want) {
  if (!sameBits(got.positions, want.positions)) return "positions differ";
  if (!sameBits(got.normals, want.normals)) return "normals differ";
  if (!sameBits(got.indices, want.indices)) return "indices differ";
  if (!sameBits(got.attributes, want.attributes)) return "attributes differ";
  if (!sameBits(got.edgeKeys, want.edgeKeys)) return "edge keys differ";
  return {};
}

}  // namespace test_support
