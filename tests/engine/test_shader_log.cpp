#include "engine/gl/gl.hpp"

#include <gtest/gtest.h>

namespace {

TEST(ShaderLog, MesaFormatGetsFileLineAndColumn) {
  const std::string out =
      engine::formatShaderLog("0:12(7): error: `foo' undeclared\n0:14(3): warning: unused\n", "shaders/a.frag");
  EXPECT_EQ(out, "shaders/a.frag:12:7: error: `foo' undeclared\nshaders/a.frag:14:3: warning: unused");
}

TEST(ShaderLog, NvidiaAndAmdFormatsGetFileAndLine) {
  EXPECT_EQ(engine::formatShaderLog("0(5) : error C1008: undefined variable \"x\"", "s.vert"),
            "s.vert:5: error C1008: undefined variable \"x\"");
  EXPECT_EQ(engine::formatShaderLog("ERROR: 0:9: 'y' : undeclared identifier", "s.vert"),
            "s.vert:9: error: 'y' : undeclared identifier");
}

TEST(ShaderLog, UnparsedLinesKeepTheFileNameAndEmptyLogsSaySo) {
  EXPECT_EQ(engine::formatShaderLog("error: linking failed", "p"), "p: error: linking failed");
  EXPECT_EQ(engine::formatShaderLog(std::string_view("\0", 1), "p"), "p: failed without a log");
}

}  // namespace
