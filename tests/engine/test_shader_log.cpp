#include "engine/gl/gl.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

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

// Several source strings (a prelude, a shared .glsl, the stage's file, as buildProgram passes
// them): the leading number picks the file; a number past the end takes the last name.
TEST(ShaderLog, SourceNumbersNameTheirFiles) {
  const std::vector<std::string> names{"<prelude>", "collide.glsl", "update.frag"};
  EXPECT_EQ(engine::formatShaderLog("0:12(5): error: syntax error\n", names), "<prelude>:12:5: error: syntax error");
  EXPECT_EQ(engine::formatShaderLog("2:7(1): warning: unused\n", names), "update.frag:7:1: warning: unused");
  EXPECT_EQ(engine::formatShaderLog("1(33) : error C0000: bad\n", names), "collide.glsl:33: error C0000: bad");
  EXPECT_EQ(engine::formatShaderLog("ERROR: 1:4: 'x' : undeclared\n", names),
            "collide.glsl:4: error: 'x' : undeclared");
  EXPECT_EQ(engine::formatShaderLog("9:3(2): error: odd\n", names), "update.frag:3:2: error: odd");
  EXPECT_EQ(engine::formatShaderLog("something else\n", names), "update.frag: something else");
}

}  // namespace
