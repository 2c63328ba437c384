#pragma once
// Small PNG charts for the benchmarks' "accuracy against time" pages (docs/*.md): an RGB canvas
// with lines, markers and a 3x5 pixel font, a log-log chart of labelled series, and a PNG writer
// (stb_image_write). Used by bench_sph, bench_surface and bench_collide_tables.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace benchplot {

struct Canvas {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // row-major, 3 bytes per pixel, white at start
  Canvas(int w, int h) : width(w), height(h), rgb(static_cast<std::size_t>(w) * h * 3, 255) {}
  void set(int x, int y, std::uint32_t color);  // 0xRRGGBB; pixels off the canvas are ignored
  void line(int x0, int y0, int x1, int y1, std::uint32_t color);
  void rect(int x0, int y0, int x1, int y1, std::uint32_t color);
  void marker(int x, int y, std::uint32_t color);
  // Text in a 3x5 font scaled by `scale`, 4 * scale pixels per character: letters (drawn
  // upper-case), digits, . , - + % / ( ) = and space; any other character is left blank.
  void text(int x, int y, const std::string& s, std::uint32_t color, int scale = 2, bool vertical = false);
};

// One curve of a chart: points drawn in the given order, joined by lines when `connect`.
// `pointLabels` (empty, or one per point) are written next to the markers.
struct Series {
  std::string label;
  std::uint32_t color = 0;
  std::vector<std::array<double, 2>> points;  // (x, y)
  bool connect = true;
  std::vector<std::string> pointLabels;
};

// A chart's plot area in canvas pixels; the axis labels and the title are drawn outside it
// (about 90 px left, 60 px below, 30 px above), the legend inside its top-right corner or, with
// legendOutside, beside it.
struct ChartFrame {
  int left = 90, top = 40, right = 690, bottom = 400;
  int legendInset = 120;  // legend markers this far left of `right`, their labels 10 px further right
  bool legendOutside = false;  // legend to the right of the plot area instead (15 px from `right`)
};

struct ChartText {
  std::string title, xLabel, yLabel;
};

// Distinct series colours (0xRRGGBB) for up to six series; the seventh repeats the first.
std::uint32_t seriesColor(std::size_t index);

// Log-log axes spanning whole decades around the positive points, one labelled tick per decade
// (`minorTicks`: unlabelled ticks at 2..9 as well), then every series and a legend. Points with a
// coordinate <= 0 or not finite cannot be placed on log axes: they are left out, and their number
// is returned so the caller can say so next to the figure.
[[nodiscard]] int drawLogLogChart(Canvas& canvas, const ChartFrame& frame, const ChartText& text, const std::vector<Series>& series,
                    bool minorTicks = false);

// Returns an empty string on success, else an error naming the file.
std::string writePng(const std::string& path, const Canvas& canvas);

}  // namespace benchplot
