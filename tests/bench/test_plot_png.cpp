// bench_plot (plot_png.hpp), the chart code behind the docs' accuracy-against-time PNGs.
#include "plot_png.hpp"

#include <gtest/gtest.h>
#include <stb_image.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include <unistd.h>

namespace {

std::uint32_t pixel(const benchplot::Canvas& c, int x, int y) {
  const std::uint8_t* p = &c.rgb[(static_cast<std::size_t>(y) * c.width + x) * 3];
  return (std::uint32_t(p[0]) << 16) | (std::uint32_t(p[1]) << 8) | p[2];
}

}  // namespace

// Points sit where log-log axes over whole decades put them; points that a log axis cannot hold
// (zero, negative, not finite) are left out and counted.
TEST(BenchPlot, LogLogChartPlacesPointsAndCountsTheOnesItCannotDraw) {
  benchplot::Canvas canvas(720, 480);
  benchplot::Series s;
  s.label = "A";
  s.color = 0x1f5fd0;
  s.connect = false;
  // x in [1, 100] and y in [0.1, 10]: the axes span exactly those decades.
  s.points = {{1.0, 0.1}, {100.0, 10.0}, {10.0, 1.0}, {0.0, 1.0}, {5.0, -1.0},
              {std::numeric_limits<double>::quiet_NaN(), 1.0}};
  const benchplot::ChartFrame frame;  // plot area x 90..690, y 40..400
  EXPECT_EQ(benchplot::drawLogLogChart(canvas, frame, {"T", "X", "Y"}, {s}), 3);  // 0, -1 and NaN
  EXPECT_EQ(pixel(canvas, 390, 220), 0x1f5fd0u);  // (10, 1): the middle of both axes
  EXPECT_EQ(pixel(canvas, 90 + 2, 400 - 2), 0x1f5fd0u);  // (1, 0.1): the lower left corner
  EXPECT_EQ(pixel(canvas, 690 - 2, 40 + 2), 0x1f5fd0u);  // (100, 10): the upper right corner
  EXPECT_EQ(pixel(canvas, 240, 310), 0xffffffu);         // nothing between them (not connected)
}

// The PNG holds the canvas' pixels; an unwritable path is an error naming it.
TEST(BenchPlot, PngRoundTripAndUnwritablePath) {
  benchplot::Canvas canvas(40, 30);
  canvas.line(0, 0, 39, 29, 0xd03020);
  // A name of this process's own: the Release and sanitizer test runs may run side by side.
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("fluiddemo_test_plot_" + std::to_string(::getpid()) + ".png");
  ASSERT_EQ(benchplot::writePng(path.string(), canvas), "");
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.string().c_str(), &w, &h, &n, 3);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 40);
  EXPECT_EQ(h, 30);
  EXPECT_TRUE(std::equal(canvas.rgb.begin(), canvas.rgb.end(), data));
  stbi_image_free(data);
  std::filesystem::remove(path);
  const std::string bad = "/nonexistent-dir/fluiddemo/plot.png";
  EXPECT_NE(benchplot::writePng(bad, canvas).find(bad), std::string::npos);
}
