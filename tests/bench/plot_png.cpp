#include "plot_png.hpp"

#include <stb_image_write.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace benchplot {
namespace {

// 3x5 glyphs, rows top to bottom, 3 bits per row (MSB = left).
int glyph(char c, int row) {
  static const char* const kDigits[10] = {"75557", "26227", "71747", "71717", "55711",
                                          "74717", "74757", "71111", "75757", "75717"};
  static const char* const kLetters[26] = {"25755", "65656", "34443", "65556", "74647", "74644", "34557",
                                           "55755", "72227", "11153", "55655", "44447", "57555", "75555",
                                           "25552", "65644", "25573", "65655", "34216", "72222", "55557",
                                           "55552", "55575", "55255", "55222", "71247"};
  const char* code = nullptr;
  if (c >= '0' && c <= '9')
    code = kDigits[c - '0'];
  else if (c >= 'A' && c <= 'Z')
    code = kLetters[c - 'A'];
  else if (c == '.')
    code = "00002";
  else if (c == ',')
    code = "00012";
  else if (c == '+')
    code = "02720";
  else if (c == '-')
    code = "00700";
  else if (c == '%')
    code = "51245";
  else if (c == '/')
    code = "11244";
  else if (c == '(')
    code = "24442";
  else if (c == ')')
    code = "42224";
  else if (c == '=')
    code = "07070";
  else
    return 0;
  return code[row] - '0';
}

}  // namespace

void Canvas::set(int x, int y, std::uint32_t color) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  std::uint8_t* p = &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
  p[0] = static_cast<std::uint8_t>(color >> 16);
  p[1] = static_cast<std::uint8_t>(color >> 8);
  p[2] = static_cast<std::uint8_t>(color);
}

void Canvas::line(int x0, int y0, int x1, int y1, std::uint32_t color) {
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int err = dx + dy;
  for (;;) {  // Bresenham
    set(x0, y0, color);
    if (x0 == x1 && y0 == y1) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x0 += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y0 += sy;
    }
  }
}

void Canvas::rect(int x0, int y0, int x1, int y1, std::uint32_t color) {
  line(x0, y0, x1, y0, color);
  line(x1, y0, x1, y1, color);
  line(x1, y1, x0, y1, color);
  line(x0, y1, x0, y0, color);
}

void Canvas::marker(int x, int y, std::uint32_t color) {
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = -3; dx <= 3; ++dx)
      if (dx * dx + dy * dy <= 10) set(x + dx, y + dy, color);
}

void Canvas::text(int x, int y, const std::string& s, std::uint32_t color, int scale, bool vertical) {
  int pen = 0;
  for (char raw : s) {
    const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(raw)));
    for (int row = 0; row < 5; ++row) {
      const int bits = glyph(c, row);
      for (int col = 0; col < 3; ++col) {
        if (!(bits & (4 >> col))) continue;
        for (int a = 0; a < scale; ++a)
          for (int b = 0; b < scale; ++b) {
            const int gx = (pen + col) * scale + a, gy = row * scale + b;
            if (vertical)
              set(x + gy, y - gx, color);
            else
              set(x + gx, y + gy, color);
          }
      }
    }
    pen += 4;
  }
}

std::uint32_t seriesColor(std::size_t index) {
  static const std::uint32_t kPalette[] = {0x1f5fd0, 0xd03020, 0x20a040, 0x9040b0, 0xd08000, 0x008080};
  return kPalette[index % std::size(kPalette)];
}

int drawLogLogChart(Canvas& cv, const ChartFrame& f, const ChartText& text, const std::vector<Series>& series,
                    bool minorTicks) {
  const int L = f.left, R = f.right, T = f.top, B = f.bottom;
  auto placeable = [](const std::array<double, 2>& p) {
    return std::isfinite(p[0]) && std::isfinite(p[1]) && p[0] > 0 && p[1] > 0;
  };
  // Whole decades around the placeable points.
  double xmin = 1e30, xmax = -1e30, ymin = 1e30, ymax = -1e30;
  int skipped = 0;
  for (const Series& s : series)
    for (const auto& p : s.points) {
      if (!placeable(p)) {
        ++skipped;
        continue;
      }
      xmin = std::min(xmin, std::log10(p[0]));
      xmax = std::max(xmax, std::log10(p[0]));
      ymin = std::min(ymin, std::log10(p[1]));
      ymax = std::max(ymax, std::log10(p[1]));
    }
  if (xmin > xmax) xmin = xmax = ymin = ymax = 0;  // nothing placeable: an empty decade
  // A point on a decade (log10 within 1e-9 of a whole number) ends the axis there.
  xmin = std::floor(xmin + 1e-9);
  xmax = std::ceil(xmax - 1e-9);
  ymin = std::floor(ymin + 1e-9);
  ymax = std::ceil(ymax - 1e-9);
  if (xmax <= xmin) xmax = xmin + 1;
  if (ymax <= ymin) ymax = ymin + 1;
  auto px = [&](double x) { return L + static_cast<int>((std::log10(x) - xmin) / (xmax - xmin) * (R - L)); };
  auto py = [&](double y) { return B - static_cast<int>((std::log10(y) - ymin) / (ymax - ymin) * (B - T)); };
  cv.rect(L, T, R, B, 0x000000);
  for (double e = xmin; e <= xmax + 1e-9; e += 1) {
    const int x = L + static_cast<int>((e - xmin) / (xmax - xmin) * (R - L));
    cv.line(x, B, x, B + 6, 0x000000);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", std::pow(10.0, e));
    cv.text(x - 8, B + 12, buf, 0x000000);
    if (minorTicks && e < xmax - 1e-9)
      for (int m = 2; m <= 9; ++m) {
        const int xm = px(m * std::pow(10.0, e));
        cv.line(xm, B, xm, B + 3, 0x000000);
      }
  }
  int widestYTick = 0;  // characters
  for (double e = ymin; e <= ymax + 1e-9; e += 1) {
    const int y = B - static_cast<int>((e - ymin) / (ymax - ymin) * (B - T));
    cv.line(L - 6, y, L, y, 0x000000);
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", std::pow(10.0, e));
    widestYTick = std::max(widestYTick, static_cast<int>(std::strlen(buf)));
    cv.text(L - 12 - 8 * static_cast<int>(std::strlen(buf)), y - 5, buf, 0x000000);
    if (minorTicks && e < ymax - 1e-9)
      for (int m = 2; m <= 9; ++m) {
        const int ym = py(m * std::pow(10.0, e));
        cv.line(L - 3, ym, L, ym, 0x000000);
      }
  }
  cv.text(L + 120, B + 40, text.xLabel, 0x000000);
  cv.text(std::min(L - 70, L - 26 - 8 * widestYTick), B - 60, text.yLabel, 0x000000, 2, true);  // left of the ticks
  cv.text(L + 10, T - 28, text.title, 0x000000);
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    bool havePrev = false;
    std::array<double, 2> prev{};
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      const auto& p = s.points[i];
      if (!placeable(p)) continue;
      cv.marker(px(p[0]), py(p[1]), s.color);
      if (s.connect && havePrev) cv.line(px(prev[0]), py(prev[1]), px(p[0]), py(p[1]), s.color);
      if (i < s.pointLabels.size() && !s.pointLabels[i].empty())
        cv.text(px(p[0]) + 6, py(p[1]) + 4, s.pointLabels[i], s.color, 1);
      prev = p;
      havePrev = true;
    }
    const int ly = T + 12 + 20 * static_cast<int>(k);
    const int lx = f.legendOutside ? R + 15 : R - f.legendInset;
    cv.marker(lx, ly + 4, s.color);
    cv.text(lx + 10, ly, s.label, s.color);
  }
  return skipped;
}

std::string writePng(const std::string& path, const Canvas& c) {
  if (stbi_write_png(path.c_str(), c.width, c.height, 3, c.rgb.data(), c.width * 3) == 0)
    return "cannot write " + path;
  return {};
}

}  // namespace benchplot
