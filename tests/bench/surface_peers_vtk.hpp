#pragma once
// The VTK half of bench_surface_peers (surface_peers.cpp): Flying Edges (Schroeder, Maynard & Geveci
// 2015, vtkFlyingEdges3D) on a caller-owned dense float lattice. Its own translation unit, compiled
// as C++17: VTK 9.1's vtkSMPTools.h does not parse as C++20 (template-id constructor declarations).
#include <cstddef>
#include <memory>

namespace benchpeers {

struct FlyingEdgesState;  // VTK objects kept between calls (image, array, filter)

// vtkSMPTools::Initialize(threads). With the TBB backend this caps the parallelism of the whole
// process (a tbb::global_control), oneTBB arenas of the extractor included: set it before each timed
// run, outside the timing.
void setThreads(int threads);

class FlyingEdges {
 public:
  FlyingEdges();
  ~FlyingEdges();
  // Triangulates the iso surface `value` of lattice[(k dims[1] + j) dims[0] + i] at origin + (i, j, k)
  // spacing, with normals unless `normals` is false, on the threads set by setThreads. Returns the
  // triangle count.
  std::size_t run(float* lattice, const int dims[3], double spacing, const double origin[3], float value,
                  bool normals = true);

 private:
  std::unique_ptr<FlyingEdgesState> state_;
};

}  // namespace benchpeers
