// Hard cases that must stay finite and sane (issue 4, "Stability tests"): stacked and
// compressed particles, a 100 m/s particle, a time step 100x too large, zero and one particle,
// particles starting inside a collider, a thin fast wall, a randomised sweep, and NaN input.
#include "fluid/sph/analytic_colliders.hpp"
#include "fluid/sph/sph_scenes.hpp"
#include "tests/sph/randomised_runs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using namespace fluid;
using randomised::emptyBox;
using randomised::finiteState;
using randomised::inside;

constexpr SphSolverKind kSolvers[] = {SphSolverKind::dfsph, SphSolverKind::wcsph};

float maxSpeed(const SphWorld& w) {
  float v = 0.0f;
  for (const glm::vec3& x : w.particles.velocity) v = std::max(v, glm::length(x));
  return v;
}

glm::vec3 extent(const SphWorld& w) {
  glm::vec3 lo(1e30f), hi(-1e30f);
  for (const glm::vec3& p : w.particles.position) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  return hi - lo;
}

TEST(SphStability, TwoHundredParticlesOnOnePointSeparate) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s = emptyBox(solver, 0.3f, 0.01f);
    for (int i = 0; i < 200; ++i) addSphParticle(s.world, glm::vec3(0.15f, 0.1f, 0.15f));
    float peak = 0.0f;
    SphStatus st = advanceSph(s.world, 0.5, [&](const SphStepStats&) { peak = std::max(peak, maxSpeed(s.world)); });
    ASSERT_TRUE(st.ok()) << st.error;
    EXPECT_TRUE(finiteState(s.world)) << sphSolverName(solver);
    EXPECT_TRUE(inside(s)) << sphSolverName(solver);
    EXPECT_LT(peak, 60.0f) << sphSolverName(solver);               // no explosion
    EXPECT_GT(extent(s.world).x, 0.04f) << sphSolverName(solver);  // they spread out
  }
}

TEST(SphStability, GridAtHalfSpacingRelaxes) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s = emptyBox(solver, 0.3f, 0.01f);
    const float half = 0.01f;  // spacing d/2 with d = 0.02
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) addSphParticle(s.world, glm::vec3(0.11f) + half * glm::vec3(x, y, z));
    float peak = 0.0f;
    ASSERT_TRUE(advanceSph(s.world, 0.5, [&](const SphStepStats&) { peak = std::max(peak, maxSpeed(s.world)); }).ok());
    EXPECT_TRUE(finiteState(s.world));
    EXPECT_TRUE(inside(s));
    // Bounded: DFSPH limits the per-step pressure push; WCSPH's release speed from 50 % (clamped)
    // compression is of the order of its sound speed.
    EXPECT_LT(peak, solver == SphSolverKind::dfsph ? 30.0f : 2.0f * s.world.params.sound_speed)
        << sphSolverName(solver);
    EXPECT_GT(extent(s.world).x, 8 * half * 1.3f) << sphSolverName(solver);  // expanded
  }
}

TEST(SphStability, ParticleInjectedAtHundredMetresPerSecond) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s;
    ASSERT_TRUE(makeSphScene("column", solver, {{"width", "0.06"}, {"height", "0.06"}, {"depth", "0.06"}}, s).ok());
    addSphParticle(s.world, glm::vec3(0.03f, 0.09f, 0.03f), glm::vec3(30.0f, -90.0f, 40.0f));  // |v| ~ 103 m/s
    SphStepStats first;
    ASSERT_TRUE(stepSph(s.world, 0.0f, &first).ok());
    EXPECT_LE(first.dt, s.world.params.cfl * 0.01f / 100.0f * 1.01f);  // CFL shrinks the step
    ASSERT_TRUE(advanceSph(s.world, 0.2, [](const SphStepStats&) {}).ok());
    EXPECT_TRUE(finiteState(s.world));
    EXPECT_TRUE(inside(s)) << sphSolverName(solver);
    EXPECT_LT(maxSpeed(s.world), 110.0f);
  }
}

TEST(SphStability, RequestedStepHundredTimesTooLarge) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s;
    ASSERT_TRUE(makeSphScene("dambreak", solver, {{"width", "0.1"}, {"spacing", "0.02"}}, s).ok());
    s.world.params.max_time_step = 0.5f;  // 100x the default 5 ms
    const double pe0 = sphPotentialEnergy(s.world);
    bool bounded = true;
    ASSERT_TRUE(advanceSph(s.world, 0.5, [&](const SphStepStats& st) {
                  bounded = bounded && st.kinetic_energy <= pe0 - sphPotentialEnergy(s.world) + 0.01 * pe0;
                  EXPECT_LT(st.dt, 0.01f);  // the CFL/force bounds still limit the step
                }).ok());
    EXPECT_TRUE(bounded) << sphSolverName(solver);
    EXPECT_TRUE(finiteState(s.world));
    EXPECT_TRUE(inside(s));
  }
}

TEST(SphStability, ZeroAndOneParticle) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s = emptyBox(solver, 0.2f, 0.01f);
    SphStepStats st;
    ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
    EXPECT_EQ(st.particles, 0u);
    EXPECT_EQ(st.kinetic_energy, 0.0f);
    ASSERT_TRUE(advanceSph(s.world, 0.1, [](const SphStepStats&) {}).ok());

    addSphParticle(s.world, glm::vec3(0.1f, 0.15f, 0.1f));
    ASSERT_TRUE(advanceSph(s.world, 1.0, [](const SphStepStats&) {}).ok());
    ASSERT_EQ(s.world.particles.size(), 1u);
    EXPECT_TRUE(finiteState(s.world));
    EXPECT_TRUE(inside(s));
    EXPECT_LT(s.world.particles.position[0].y, 0.05f) << sphSolverName(solver);  // fell to the floor
  }
}

TEST(SphStability, ParticlesStartingInsideAColliderArePushedOut) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s = emptyBox(solver, 0.4f, 0.01f);
    s.world.params.gravity = glm::vec3(0.0f);
    auto ball = std::make_shared<SphereShape>(0.08f);
    SphCollider c;
    c.shape = ball;
    c.pose.translation = glm::vec3(0.2f);
    s.world.colliders.push_back(c);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.07f, 0.07f);
    for (int i = 0; i < 150; ++i) {
      glm::vec3 o(u(rng), u(rng), u(rng));
      if (glm::length(o) < 0.075f) addSphParticle(s.world, glm::vec3(0.2f) + o);
    }
    for (int step = 0; step < 3; ++step) ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
    for (const glm::vec3& p : s.world.particles.position)
      EXPECT_GE(glm::length(p - glm::vec3(0.2f)), 0.08f - 1e-5f) << sphSolverName(solver);
  }
}

TEST(SphStability, EmittersDoNotCreateParticlesInsideAColliderAndStayCalm) {
  // An emitter buried in a sphere emits nothing; one just off its surface emits only the lattice points
  // with room for a particle outside it (a particle created inside the boundary would start at up
  // to twice rho_0, and WCSPH's Tait pressure fires it off at km/s).
  for (SphSolverKind solver : kSolvers) {
    std::size_t without_collider = 0;
    for (const float offset : {-1.0f, 0.0f, 0.065f}) {  // -1: the surface case without the sphere
      SphScene s = emptyBox(solver, 0.5f, 0.01f);
      if (offset >= 0.0f) {
        SphCollider c;
        c.shape = std::make_shared<SphereShape>(0.06f);
        c.pose.translation = glm::vec3(0.25f);
        c.integrate_pose = false;
        s.world.colliders.push_back(c);
      }
      SphEmitter e;
      e.position = glm::vec3(0.25f + (offset < 0.0f ? 0.065f : offset), 0.25f, 0.25f);
      e.direction = glm::vec3(1.0f, 0.0f, 0.0f);
      e.speed = 1.0f;
      e.radius = 0.03f;
      e.rate = 2000.0f;
      s.world.emitters.push_back(e);
      std::size_t emitted = 0;
      float fastest = 0.0f;
      for (int step = 0; step < 100; ++step) {
        SphStepStats st;
        ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
        emitted += st.emitted;
        for (const glm::vec3& v : s.world.particles.velocity) fastest = std::max(fastest, glm::length(v));
      }
      if (offset < 0.0f) {
        without_collider = emitted;
      } else if (offset == 0.0f) {
        EXPECT_EQ(emitted, 0u) << sphSolverName(solver);
      } else {
        // The disc straddles the surface: the points without room outside the sphere are dropped.
        EXPECT_GT(emitted, 0u) << sphSolverName(solver);
        EXPECT_LT(emitted, without_collider) << sphSolverName(solver);
      }
      EXPECT_LT(fastest, 5.0f) << sphSolverName(solver);  // jet at 1 m/s: nothing fired off
    }
  }
}

TEST(SphStability, ABuriedNozzleDoesNotPackParticlesIntoTheFluid) {
  // A slow jet aimed at the floor from just above it: the water piles up under the nozzle and soon
  // buries it. Layers placed into that pile would start compressed, and the pressure solve would
  // turn the compression into kinetic energy the jet never brought (the randomised runs broke their
  // energy bound this way: 16 of 1600 before emitters skipped points next to existing particles).
  // The total energy must stay below what the emitter supplied.
  for (SphSolverKind solver : kSolvers) {
    SphScene s = emptyBox(solver, 0.3f, 0.008f);
    SphEmitter e;
    e.position = glm::vec3(0.15f, 0.03f, 0.15f);
    e.direction = glm::vec3(0.0f, -1.0f, 0.0f);
    e.speed = 0.5f;
    e.radius = 0.025f;
    e.rate = 3000.0f;
    s.world.emitters.push_back(e);
    const double m = sphParticleMass(s.world.params);
    double injected = 0.0, worst_ratio = 0.0;
    std::size_t emitted = 0;
    for (int step = 0; step < 5000 && s.world.time < 0.4; ++step) {  // WCSPH takes ~4x the steps
      SphStepStats st;
      ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
      emitted += st.emitted;
      // What a particle brings: its kinetic energy plus potential energy at its spawn height (at
      // most the nozzle plus a layer's travel, d).
      injected += double(st.emitted) * m * (0.5 * e.speed * e.speed + 9.81 * (e.position.y + 0.016));
      const double energy = st.kinetic_energy + sphPotentialEnergy(s.world);
      if (injected > 0.0) worst_ratio = std::max(worst_ratio, energy / injected);
    }
    // The nozzle emits a pile and is then blocked; the fluid never holds more energy than it was
    // given (a particle placed into compressed fluid would turn that compression into energy).
    EXPECT_GT(emitted, 40u) << sphSolverName(solver);
    EXPECT_LE(worst_ratio, 1.0) << sphSolverName(solver);
  }
}

TEST(SphStability, ANewLayerDoesNotSqueezeFluidPressedAgainstACollider) {
  // A 3 x 3 patch (r = 10 mm, d = 20 mm) pressed against the floor closer than the rest distance r,
  // as a jet running onto a solid leaves it, and a downward nozzle 1.2 d above its centre (room
  // for a particle: more than r from the floor and 0.99 d from the patch). No gravity, so the patch
  // stays put until the layer is due. At 6 mm the patch is below rho_0, but a particle d above its
  // centre would bring it to 1.0176 rho_0 (the boundary volume already counts for most of the
  // missing neighbours), so the layer is not placed there. At 6.5 and 8 mm there is room: the
  // layer is placed and its step starts without compression.
  for (SphSolverKind solver : kSolvers) {
    for (const float gap : {0.006f, 0.0065f, 0.008f}) {
      SphScene s = emptyBox(solver, 0.3f, 0.01f);
      s.world.params.gravity = glm::vec3(0.0f);
      const float d = sphSpacing(s.world.params);
      for (int i = -1; i <= 1; ++i)
        for (int k = -1; k <= 1; ++k) addSphParticle(s.world, glm::vec3(0.15f + i * d, gap, 0.15f + k * d));
      SphEmitter e;
      e.position = glm::vec3(0.15f, gap + 1.2f * d, 0.15f);
      e.direction = glm::vec3(0.0f, -1.0f, 0.0f);
      e.speed = 2.0f;
      e.radius = 0.0f;  // one particle per layer, one layer (due at t = d / speed = 10 ms)
      e.end_time = 0.012f;
      s.world.emitters.push_back(e);
      std::size_t emitted = 0;
      for (int step = 0; step < 100; ++step) {
        SphStepStats st;
        ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
        emitted += st.emitted;
        // The density pass runs after the emitters: the step's start state includes the new layer.
        if (st.emitted > 0) {
          EXPECT_EQ(st.max_density_error, 0.0f) << sphSolverName(solver) << " gap " << gap << " step " << step;
        }
      }
      EXPECT_EQ(emitted, gap == 0.006f ? 0u : 1u) << sphSolverName(solver) << " gap " << gap;
    }
  }
}

TEST(SphStability, AFreeJetEmitsEveryLatticePointOfEveryLayer) {
  // The density test must not cost a free jet any particle. Layers exactly d apart (rate high enough
  // that the interval is d / speed) complete lattice neighbourhoods whose SPH density is rho_0 to
  // the last bit (sphParticleMass), so a test without slack for rounding dropped points here: with
  // discs of radius 1.5 d, 2.5 d and 4 d it emitted 87 of 90, 206 of 210 and 478 of 490 particles.
  for (SphSolverKind solver : kSolvers) {
    for (const float radiusInSpacings : {1.5f, 2.5f, 4.0f}) {
      for (const bool gravity : {false, true}) {
        SphScene s = emptyBox(solver, 1.0f, 0.01f);
        s.world.params.gravity = gravity ? glm::vec3(0.0f, -9.81f, 0.0f) : glm::vec3(0.0f);
        s.world.params.max_particles = 20000;
        const float d = sphSpacing(s.world.params);
        SphEmitter e;
        e.position = glm::vec3(0.5f, 0.2f, 0.5f);
        e.direction = glm::vec3(0.0f, 1.0f, 0.0f);  // up, into free space
        e.speed = 2.0f;
        e.radius = radiusInSpacings * d;
        e.rate = 1e5f;  // interval d / speed: one layer per d of travel
        s.world.emitters.push_back(e);
        // A whole disc: the lattice points within the radius, as forDiscLattice places them.
        std::size_t disc = 0;
        const int n = int(radiusInSpacings) + 1;
        for (int i = -n; i <= n; ++i)
          for (int k = -n; k <= n; ++k)
            if (float(i * i + k * k) * d * d <= e.radius * e.radius + 1e-6f * d * d) ++disc;
        std::size_t emitted = 0;
        for (int step = 0; step < 3000 && emitted < 10 * disc; ++step) {
          SphStepStats st;
          ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
          EXPECT_EQ(st.emitted % disc, 0u) << sphSolverName(solver) << " radius " << radiusInSpacings << " d, step "
                                           << step << ": a layer lost points";
          emitted += st.emitted;
        }
        ASSERT_GE(emitted, 10 * disc) << "fewer than 10 layers emitted";
        EXPECT_EQ(emitted % disc, 0u) << sphSolverName(solver) << " radius " << radiusInSpacings << " d, gravity "
                                      << gravity << ": " << emitted << " particles, discs of " << disc;
      }
    }
  }
}

TEST(SphStability, NozzleJustAboveASphereInjectsNoEnergy) {
  // Pins a randomised run (its drawn values written out; DFSPH): a downward nozzle 1 cm above a
  // sphere, where a new layer would squeeze the film sliding on the sphere and DFSPH would turn
  // that compression into speed.
  SphScene s = emptyBox(SphSolverKind::dfsph, 0.5f, 0.00626970967f);
  SphParams& p = s.world.params;
  p.viscosity = 0.018705206f;
  p.cfl = 0.153934419f;
  p.max_time_step = 0.0161745921f;
  p.max_density_error = 0.00287761702f;
  p.max_particles = 1500;
  SphEmitter e;
  e.position = glm::vec3(0.303961903f, 0.353126138f, 0.364329219f);
  e.direction = glm::vec3(0.00665724277f, -0.925450563f, 0.0952626467f);
  e.speed = 2.93640351f;
  e.radius = 0.0163406134f;
  e.rate = 872.543579f;
  s.world.emitters.push_back(e);
  SphCollider c;
  c.shape = std::make_shared<SphereShape>(0.0958171487f);
  c.pose.translation = glm::vec3(0.275547475f, 0.254085869f, 0.340610921f);
  s.world.colliders.push_back(c);
  float fastest = 0.0f, compression_at_emission = 0.0f;
  const double m = sphParticleMass(p);
  double injected = 0.0;
  for (int step = 0; step < 200; ++step) {
    SphStepStats st;
    ASSERT_TRUE(stepSph(s.world, 0.0f, &st).ok());
    injected += st.emitted * m * (0.5 * e.speed * e.speed + 9.81 * (e.position.y + 0.1));
    const double energy = st.kinetic_energy + sphPotentialEnergy(s.world);
    ASSERT_LE(energy, injected * 1.01 + 1e-9) << "step " << step;  // the bound of randomised::stepRun
    if (st.emitted > 0) compression_at_emission = std::max(compression_at_emission, st.max_density_error);
    fastest = std::max(fastest, maxSpeed(s.world));
  }
  EXPECT_EQ(compression_at_emission, 0.0f);
  // A single particle from the nozzle reaches at most sqrt(v^2 + 2 g h) = 3.94 m/s at the floor;
  // pressure may pass some energy between particles, hence 5 m/s. The squeeze launched 9.6-15 m/s.
  EXPECT_LT(fastest, 5.0f);
  EXPECT_TRUE(finiteState(s.world));
  EXPECT_TRUE(inside(s));
}

TEST(SphStability, ThinFastWallDoesNotLetParticlesThrough) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s = emptyBox(solver, 1.0f, 0.01f);
    s.world.params.gravity = glm::vec3(0.0f);
    // A 4 mm thick wall (less than the 20 mm spacing) sweeping +x at 20 m/s through a particle slab.
    auto slab = std::make_shared<BoxShape>(glm::vec3(0.002f, 0.5f, 0.5f));
    SphCollider wall;
    wall.shape = slab;
    wall.boundary_pressure = false;
    wall.pose.translation = glm::vec3(0.05f, 0.5f, 0.5f);
    wall.pose.linear_velocity = glm::vec3(20.0f, 0.0f, 0.0f);
    s.world.colliders.push_back(wall);
    for (int z = 0; z < 5; ++z)
      for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x) addSphParticle(s.world, glm::vec3(0.3f, 0.4f, 0.4f) + 0.02f * glm::vec3(x, y, z));
    // Run while the wall crosses x = 0.3 .. 0.7.
    while (s.world.colliders.back().pose.translation.x < 0.8f) {
      ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
      const float wall_x = s.world.colliders.back().pose.translation.x;
      for (const glm::vec3& p : s.world.particles.position)
        ASSERT_GE(p.x, wall_x + 0.002f - 1e-4f)
            << sphSolverName(solver) << " t = " << s.world.time << " dt = " << s.world.last_dt;
    }
    EXPECT_TRUE(finiteState(s.world));
  }
}

TEST(SphStability, RandomisedRunsStayFiniteWithBoundedEnergy) {
  // One seed of tests/sph/randomised_runs.hpp (ranges documented there); a sweep over other
  // seeds: bench_sph seeds.
  std::mt19937 rng(20240521), dfsph_rng(20261121);
  for (int run = 0; run < randomised::kRunsPerSeed; ++run) {
    SphScene s = randomised::drawRun(run, rng, dfsph_rng);
    const randomised::RunOutcome outcome = randomised::stepRun(s, randomised::kStepsPerRun);
    EXPECT_TRUE(outcome.ok) << "run " << run << " step " << outcome.step << ": " << outcome.what;
  }
}

TEST(SphStability, NonFiniteInputIsReportedNotSpread) {
  for (SphSolverKind solver : kSolvers) {
    SphScene s;
    ASSERT_TRUE(makeSphScene("dambreak", solver, {{"width", "0.1"}, {"spacing", "0.02"}}, s).ok());
    for (int i = 0; i < 5; ++i) ASSERT_TRUE(stepSph(s.world, 0.0f).ok());
    const std::size_t victim = 17;
    const std::uint32_t id = s.world.particles.id[victim];
    s.world.particles.velocity[victim].y = std::numeric_limits<float>::quiet_NaN();
    const auto before = s.world.particles.position;
    const SphStatus st = stepSph(s.world, 0.0f);
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.error.find("particle id " + std::to_string(id)), std::string::npos) << st.error;
    EXPECT_NE(st.error.find("step 5"), std::string::npos) << st.error;
    EXPECT_EQ(before, s.world.particles.position);  // nothing moved, nothing spread
    s.world.particles.velocity[victim].y = 0.0f;
    s.world.particles.position[3].x = std::numeric_limits<float>::infinity();
    EXPECT_FALSE(stepSph(s.world, 0.0f).ok());
  }
}

TEST(SphStability, NonFiniteEmitterOrColliderPoseIsRejected) {
  SphScene s = emptyBox(SphSolverKind::dfsph, 0.2f, 0.01f);
  SphEmitter e;
  e.position = glm::vec3(0.1f, std::numeric_limits<float>::quiet_NaN(), 0.1f);
  s.world.emitters.push_back(e);
  SphStatus st = stepSph(s.world, 0.0f);
  EXPECT_NE(st.error.find("emitter 0"), std::string::npos) << st.error;
  s.world.emitters.clear();
  s.world.colliders[0].pose.linear_velocity.x = std::numeric_limits<float>::infinity();
  st = stepSph(s.world, 0.0f);
  EXPECT_NE(st.error.find("collider 0"), std::string::npos) << st.error;
  EXPECT_EQ(s.world.particles.size(), 0u);
}

TEST(SphStability, BadParametersAreRejectedWithTheirName) {
  SphScene s = emptyBox(SphSolverKind::dfsph, 0.2f, 0.01f);
  s.world.params.cfl = std::numeric_limits<float>::quiet_NaN();
  SphStatus st = stepSph(s.world, 0.0f);
  EXPECT_NE(st.error.find("cfl"), std::string::npos) << st.error;
  s.world.params.cfl = 0.4f;
  s.world.params.particle_radius = -1.0f;
  st = stepSph(s.world, 0.0f);
  EXPECT_NE(st.error.find("particle_radius"), std::string::npos) << st.error;
  s.world.params.particle_radius = 0.01f;
  s.world.params.max_particles = std::size_t{1} << 28;  // the pair loops' 32-bit byte offsets
  st = stepSph(s.world, 0.0f);
  EXPECT_NE(st.error.find("max_particles"), std::string::npos) << st.error;
  s.world.params.max_particles = (std::size_t{1} << 28) - 1;
  EXPECT_TRUE(stepSph(s.world, 0.0f).ok());
}

}  // namespace
