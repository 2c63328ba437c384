// Mesh a particle file to OBJ (or .ply/.vtk/.vtu) with fluid/surface's marching slices.
//   mesh_particles particles.xyz out.obj [rc threshold cube]
// rc: the field's cutoff radius (world units), as `fluiddemo mesh --rc`; defaults as SurfaceParams.
#include "fluid/io/particle_io.hpp"
#include "fluid/surface/marching_slices.hpp"
#include "fluid/surface/mesh_io.hpp"

#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
  if (argc != 3 && argc != 6) {
    std::fprintf(stderr, "usage: %s particles.xyz out.obj [rc threshold cube]\n", argv[0]);
    return 2;
  }
  fluid::SurfaceParams params;  // rc 3, threshold 0.2, cube 1, all threads
  if (argc == 6) {
    params.rc = std::strtof(argv[3], nullptr);
    params.threshold = std::strtof(argv[4], nullptr);
    params.cube = std::strtof(argv[5], nullptr);
  }

  fluid::ParticlePositions particles;
  if (const fluid::IoStatus read = fluid::readParticleFile(argv[1], particles); !read.ok()) {
    std::fprintf(stderr, "%s\n", read.error.c_str());
    return 1;
  }

  // One extractor, reused across frames in a real program: it keeps its scratch memory.
  fluid::SurfaceExtractor extractor;
  fluid::SurfaceMesh mesh;
  const fluid::SurfaceInput input{fluid::pointView(particles)};
  if (const fluid::SurfaceStatus st = extractor.extract(input, params, mesh); !st.ok()) {
    std::fprintf(stderr, "%s: %s\n", argv[1], st.error.c_str());
    return 1;
  }

  // Refuses to replace an existing file (MeshWriteOptions::overwrite).
  if (const fluid::IoStatus written = fluid::writeSurfaceMesh(argv[2], mesh); !written.ok()) {
    std::fprintf(stderr, "%s\n", written.error.c_str());
    return 1;
  }
  std::printf("%s: %zu particles -> %zu triangles in %s\n", argv[1], particles.size(), mesh.indices.size() / 3,
              argv[2]);
  return 0;
}
