#include "engine/profile/profiler.hpp"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

namespace {

using engine::Phase;

TEST(Profiler, ScopedPhaseMeasuresAtLeastTheSleptTime) {
  engine::Profiler p;
  engine::beginFrame(p);
  {
    engine::ScopedPhase scope(p, Phase::physics);
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
  engine::endFrame(p);
  EXPECT_GE(engine::historyAt(p, Phase::physics, 0), 3.0f);
  EXPECT_EQ(p.stats[static_cast<int>(Phase::physics)].frames, 1u);
  EXPECT_GE(p.frame_history[0], engine::historyAt(p, Phase::physics, 0));
}

TEST(Profiler, SameFrameScopesAreSummedAndUnusedPhasesDoNotCount) {
  engine::Profiler p;
  engine::beginFrame(p);
  engine::addPhaseTime(p, Phase::render, 1.5);
  engine::addPhaseTime(p, Phase::render, 2.0);
  engine::endFrame(p);
  EXPECT_FLOAT_EQ(engine::historyAt(p, Phase::render, 0), 3.5f);
  EXPECT_EQ(p.stats[static_cast<int>(Phase::fluid)].frames, 0u);
  EXPECT_DOUBLE_EQ(engine::phaseMeanMs(p, Phase::fluid), 0.0);
  EXPECT_EQ(p.frames, 1u);
}

TEST(Profiler, StatisticsAndHistoryRingWrap) {
  engine::Profiler p;
  const int frames = engine::Profiler::kHistory + 7;
  for (int f = 0; f < frames; ++f) {
    engine::beginFrame(p);
    engine::addPhaseTime(p, Phase::ui, static_cast<double>(f));
    engine::endFrame(p);
  }
  EXPECT_EQ(p.filled, engine::Profiler::kHistory);
  EXPECT_FLOAT_EQ(engine::historyAt(p, Phase::ui, 0), static_cast<float>(frames - 1));
  EXPECT_FLOAT_EQ(engine::historyAt(p, Phase::ui, engine::Profiler::kHistory - 1),
                  static_cast<float>(frames - engine::Profiler::kHistory));
  EXPECT_FLOAT_EQ(engine::historyAt(p, Phase::ui, engine::Profiler::kHistory), 0.0f);  // beyond the ring
  EXPECT_DOUBLE_EQ(engine::phaseMeanMs(p, Phase::ui), (frames - 1) / 2.0);
  EXPECT_DOUBLE_EQ(p.stats[static_cast<int>(Phase::ui)].max_ms, frames - 1.0);
  EXPECT_EQ(engine::phaseName(Phase::meshing), "meshing");
}

}  // namespace

// The overlay's red markers (engine/ui/overlay.cpp draws one per entry of flaggedFramesAgo): the
// list holds exactly the flagged frames, as frames ago, oldest first, also after the ring wraps.
TEST(Profiler, FlaggedFramesAreExactlyTheMarkedOnes) {
  engine::Profiler p;
  engine::flagFrame(p);  // outside a frame: ignored
  const int frames = engine::Profiler::kHistory + 10;
  const auto marked = [](int f) { return f % 7 == 3 || f == 0; };
  for (int f = 0; f < frames; ++f) {
    engine::beginFrame(p);
    if (marked(f)) {
      engine::flagFrame(p);
      engine::flagFrame(p);  // twice in a frame: still one marker
    }
    engine::endFrame(p);
  }
  std::vector<int> want;
  std::uint64_t total = 0;
  for (int f = 0; f < frames; ++f) {
    total += marked(f) ? 1 : 0;
    const int ago = frames - 1 - f;
    if (marked(f) && ago < engine::Profiler::kHistory) want.push_back(ago);
  }
  std::vector<int> got{12345};  // refilled, not appended to
  engine::flaggedFramesAgo(p, got);
  EXPECT_EQ(got, want);
  EXPECT_EQ(p.flagged_frames, total);
  // Frame 0 was flagged but has left the ring; an unflagged frame after clears nothing.
  engine::beginFrame(p);
  engine::endFrame(p);
  engine::flaggedFramesAgo(p, got);
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back(), want.back() + 1);
  EXPECT_EQ(p.flagged_frames, total);
}
