// The two field routes (SurfaceParams::fieldRoute): the slice-row splat (default) and the paper's §6
// column cache sum the same particles in the same order with the same float expressions, so they
// must give the same mesh bit for bit, on the data sets and on the hard cases, for every sweep frame.
#include "fluid/surface/marching_slices.hpp"
#include "mesh_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>
#include <vector>

using namespace surface_test;

namespace {

fluid::SurfaceMesh meshBy(fluid::SurfaceFieldRoute route, const fluid::SurfaceInput& in, fluid::SurfaceParams p) {
  p.fieldRoute = route;
  fluid::SurfaceExtractor ex;
  fluid::SurfaceMesh m;
  const fluid::SurfaceStatus st = ex.extract(in, p, m);
  EXPECT_TRUE(st.ok()) << st.error;
  return m;
}

void expectSameMesh(const fluid::SurfaceInput& in, const fluid::SurfaceParams& p, const std::string& what,
                    std::size_t minTriangles) {
  const fluid::SurfaceMesh rows = meshBy(fluid::SurfaceFieldRoute::sliceRows, in, p);
  const fluid::SurfaceMesh cache = meshBy(fluid::SurfaceFieldRoute::columnCache, in, p);
  EXPECT_GE(rows.indices.size() / 3, minTriangles) << what;
  EXPECT_TRUE(rows.positions == cache.positions) << what;
  EXPECT_TRUE(rows.normals == cache.normals) << what;
  EXPECT_TRUE(rows.indices == cache.indices) << what;
  EXPECT_TRUE(rows.edgeKeys == cache.edgeKeys) << what;
  EXPECT_EQ(rows.stats.cornersEvaluated, cache.stats.cornersEvaluated) << what;
  EXPECT_EQ(rows.stats.seedEvaluations, cache.stats.seedEvaluations) << what;
}

}  // namespace

TEST(FieldRoutes, SliceRowsAndColumnCacheGiveTheSameMeshOnTheDataSets) {
  const std::tuple<const char*, float> sets[] = {
      {"fountain.xyz", 1.0f}, {"blob.xyz", 0.3f}, {"explosion.xyz", 0.6f}, {"spray.xyz", 1.0f}};
  for (const auto& [name, cube] : sets) {
    const fluid::ParticlePositions ps = loadSet(name);
    for (int order = 0; order < 2; ++order) {
      fluid::SurfaceParams p;
      p.cube = cube;
      p.threads = 2;
      if (order) {  // a rotated sweep frame
        p.order = fluid::SurfaceOrder::backToFront;
        p.eye = {40.0f, -25.0f, 10.0f};
        p.viewDir = {-0.8f, 0.5f, -0.2f};
      }
      expectSameMesh(inputOf(ps), p, std::string(name) + " order " + std::to_string(order), 1000);
    }
  }
}

TEST(FieldRoutes, SameMeshOnTheHardCases) {
  {  // upright bowl (sweep reversals, Fig. 4b), small blocks (many seams)
    std::vector<float> x, y, z;
    for (float th = 0.0f; th < 1.55f; th += 0.09f)
      for (float ph = 0.0f; ph < 6.28f; ph += 0.09f / std::max(0.09f, std::sin(th))) {
        x.push_back(16.0f + 8.0f * std::sin(th) * std::cos(ph));
        y.push_back(16.0f + 8.0f * std::sin(th) * std::sin(ph));
        z.push_back(-16.0f - 8.0f * std::cos(th));
      }
    fluid::SurfaceParams p;
    p.cube = 0.5f;
    for (int block : {64, 12}) {
      p.blockCubes = block;
      expectSameMesh({x, y, z, {}, {}, {}}, p, "bowl, blockCubes " + std::to_string(block), 1000);
    }
  }
  {  // far from the origin
    fluid::ParticlePositions ps = loadSet("blob.xyz");
    for (std::size_t i = 0; i < ps.size(); ++i) {
      ps.x[i] += 1e5f;
      ps.y[i] -= 1e5f;
      ps.z[i] += 1e5f;
    }
    fluid::SurfaceParams p;
    p.cube = 0.3f;
    p.originX = 1e5;
    p.originY = -1e5;
    p.originZ = 1e5;
    expectSameMesh(inputOf(ps), p, "blob offset by 1e5", 1000);
  }
  {  // corner values exactly T (see MarchingSlices.FieldExactlyEqualToThresholdAtCorners)
    const std::vector<float> x = {0, 3}, y = {0, 0}, z = {0, 1};
    fluid::SurfaceParams p;
    p.rc = 2.0f;
    p.threshold = 0.140625f;
    expectSameMesh({x, y, z, {}, {}, {}}, p, "values exactly T", 8);
  }
  {  // coincident particles; particles on corners and block faces; varying strength and radius
    const std::vector<float> x(7, 1.25f), y(7, -2.5f), z(7, 0.75f);
    fluid::SurfaceParams p;
    p.cube = 0.25f;
    expectSameMesh({x, y, z, {}, {}, {}}, p, "coincident", 100);
    std::vector<float> cx, cy, cz, strength, scale;
    for (float a : {-4.0f, -2.5f, 0.0f, 1.5f, 4.0f, 4.5f, 8.0f})
      for (float b : {-4.0f, -1.0f, 0.0f, 4.0f})
        for (float c : {0.0f, 2.0f, 4.0f}) {
          cx.push_back(a), cy.push_back(b), cz.push_back(c);
          strength.push_back(0.6f + 0.1f * float(cx.size() % 7));
          scale.push_back(0.7f + 0.05f * float(cx.size() % 9));
        }
    p.cube = 0.5f;
    p.blockCubes = 5;
    expectSameMesh({cx, cy, cz, {}, {}, {}}, p, "on corners, blockCubes 5", 100);
    expectSameMesh({cx, cy, cz, strength, scale, {}}, p, "strength and radius scale", 100);
  }
}
