// The shared blast model (fluid/core/blast.hpp): spherical 1/r^2 spreading, capped in the core,
// zero beyond reach with a continuous taper, a defined direction at the centre, bad fields named.
#include "fluid/core/blast.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace {

fluid::Blast unitBlast() {
  fluid::Blast blast;
  blast.centre = {1.0f, 2.0f, 3.0f};
  blast.impulse_at_1m = 100.0f;
  blast.core_radius = 0.2f;
  blast.reach = 5.0f;
  return blast;
}

TEST(Blast, ImpulsePerAreaFallsAsTheInverseSquareOfDistance) {
  const fluid::Blast blast = unitBlast();
  EXPECT_FLOAT_EQ(fluid::blastImpulsePerArea(blast, 1.0f), 100.0f);
  EXPECT_FLOAT_EQ(fluid::blastImpulsePerArea(blast, 2.0f), 25.0f);
  EXPECT_FLOAT_EQ(fluid::blastImpulsePerArea(blast, 0.5f), 400.0f);
}

TEST(Blast, ImpulseIsCappedInsideTheCoreAndFiniteAtTheCentre) {
  const fluid::Blast blast = unitBlast();
  const float at_core = fluid::blastImpulsePerArea(blast, blast.core_radius);
  EXPECT_FLOAT_EQ(at_core, 100.0f / (0.2f * 0.2f));
  EXPECT_FLOAT_EQ(fluid::blastImpulsePerArea(blast, 0.0f), at_core);
  EXPECT_FLOAT_EQ(fluid::blastImpulsePerArea(blast, 0.05f), at_core);
}

TEST(Blast, ImpulseTapersContinuouslyToZeroAtReach) {
  const fluid::Blast blast = unitBlast();
  EXPECT_EQ(fluid::blastImpulsePerArea(blast, blast.reach), 0.0f);
  EXPECT_EQ(fluid::blastImpulsePerArea(blast, 7.0f), 0.0f);
  // Continuous where the taper starts and monotonically falling through the band.
  const float start = 0.8f * blast.reach;
  EXPECT_NEAR(fluid::blastImpulsePerArea(blast, start - 1e-4f), fluid::blastImpulsePerArea(blast, start + 1e-4f), 1e-2f);
  float previous = fluid::blastImpulsePerArea(blast, start);
  for (float d = start + 0.05f; d < blast.reach; d += 0.05f) {
    const float value = fluid::blastImpulsePerArea(blast, d);
    EXPECT_LT(value, previous) << d;
    previous = value;
  }
  EXPECT_LT(fluid::blastImpulsePerArea(blast, blast.reach - 1e-3f), 1e-3f);
}

TEST(Blast, VelocityChangePointsAwayFromTheCentreAndIsCapped) {
  const fluid::Blast blast = unitBlast();
  const glm::vec3 dv = fluid::blastVelocityChange(blast, blast.centre + glm::vec3(0, 0, 2), 0.02f, 50.0f);
  EXPECT_FLOAT_EQ(dv.z, 25.0f * 0.02f);
  EXPECT_EQ(dv.x, 0.0f);
  EXPECT_EQ(dv.y, 0.0f);
  // At the centre itself: straight up, capped.
  const glm::vec3 at_centre = fluid::blastVelocityChange(blast, blast.centre, 1.0f, 30.0f);
  EXPECT_EQ(at_centre, glm::vec3(0.0f, 30.0f, 0.0f));
}

TEST(Blast, ValidationNamesTheBadField) {
  fluid::Blast blast = unitBlast();
  EXPECT_EQ(fluid::validateBlast(blast), "");
  blast.centre.y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(fluid::validateBlast(blast).find("blast.centre"), std::string::npos);
  blast = unitBlast();
  blast.impulse_at_1m = -1.0f;
  EXPECT_NE(fluid::validateBlast(blast).find("blast.impulse_at_1m = -1"), std::string::npos);
  blast = unitBlast();
  blast.core_radius = 0.0f;
  EXPECT_NE(fluid::validateBlast(blast).find("blast.core_radius"), std::string::npos);
  blast = unitBlast();
  blast.reach = 0.1f;
  EXPECT_NE(fluid::validateBlast(blast).find("blast.reach"), std::string::npos);
  blast = unitBlast();
  blast.reach = std::numeric_limits<float>::infinity();
  EXPECT_NE(fluid::validateBlast(blast).find("blast.reach"), std::string::npos);
}

}  // namespace
