#include "sph_png.hpp"

#include <array>
#include <cctype>
#include <cstdlib>
#include <fstream>

namespace sphbench {
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

std::uint32_t crc32(const std::uint8_t* data, std::size_t n, std::uint32_t crc = 0) {
  static std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}

void chunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& body) {
  put32(out, static_cast<std::uint32_t>(body.size()));
  std::vector<std::uint8_t> typed(type, type + 4);
  typed.insert(typed.end(), body.begin(), body.end());
  out.insert(out.end(), typed.begin(), typed.end());
  put32(out, crc32(typed.data(), typed.size()));
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

std::string writePng(const std::string& path, const Canvas& c) {
  std::vector<std::uint8_t> raw;
  raw.reserve(static_cast<std::size_t>(c.height) * (c.width * 3 + 1));
  for (int y = 0; y < c.height; ++y) {
    raw.push_back(0);  // filter: none
    raw.insert(raw.end(), c.rgb.begin() + static_cast<std::ptrdiff_t>(y) * c.width * 3,
               c.rgb.begin() + static_cast<std::ptrdiff_t>(y + 1) * c.width * 3);
  }
  // zlib stream of stored deflate blocks (RFC 1950/1951).
  std::vector<std::uint8_t> z{0x78, 0x01};
  std::size_t pos = 0;
  do {
    const std::size_t len = std::min<std::size_t>(65535, raw.size() - pos);
    const bool last = pos + len == raw.size();
    z.push_back(last ? 1 : 0);
    z.push_back(static_cast<std::uint8_t>(len));
    z.push_back(static_cast<std::uint8_t>(len >> 8));
    z.push_back(static_cast<std::uint8_t>(~len));
    z.push_back(static_cast<std::uint8_t>(~len >> 8));
    z.insert(z.end(), raw.begin() + static_cast<std::ptrdiff_t>(pos),
             raw.begin() + static_cast<std::ptrdiff_t>(pos + len));
    pos += len;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;
  for (std::uint8_t v : raw) {
    a = (a + v) % 65521u;
    b = (b + a) % 65521u;
  }
  put32(z, (b << 16) | a);

  std::vector<std::uint8_t> png{0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  std::vector<std::uint8_t> ihdr;
  put32(ihdr, static_cast<std::uint32_t>(c.width));
  put32(ihdr, static_cast<std::uint32_t>(c.height));
  ihdr.insert(ihdr.end(), {8, 2, 0, 0, 0});  // 8-bit RGB
  chunk(png, "IHDR", ihdr);
  chunk(png, "IDAT", z);
  chunk(png, "IEND", {});
  std::ofstream out(path, std::ios::binary);
  if (!out) return "cannot write " + path;
  out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  return out ? std::string() : "write failed: " + path;
}

}  // namespace sphbench
