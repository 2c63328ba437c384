#pragma once
// CSV output of the benchmarks: the data behind the docs' charts, which scripts/plots/*.py draw with
// matplotlib. One header row, then one row per table row; fields are quoted (RFC 4180) when they
// hold a comma, a quote or a line break, and numbers are written with enough digits to round-trip.
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace benchcsv {

inline std::string field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

inline std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

// Number of chart points a log axis cannot hold (a coordinate <= 0 or not finite), so the page can
// say what the chart leaves out next to the table it draws.
inline bool drawableOnLogAxes(double x, double y) { return x > 0.0 && y > 0.0 && x < 1e300 && y < 1e300; }

// Writes `table` to `path`; returns "" on success, else an error naming the file.
inline std::string write(const std::string& path, const Table& table) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  auto line = [&out](const std::vector<std::string>& fields) {
    for (std::size_t k = 0; k < fields.size(); ++k) out << (k ? "," : "") << field(fields[k]);
    out << "\n";
  };
  line(table.header);
  for (const auto& row : table.rows) {
    if (row.size() != table.header.size())
      return path + ": a row has " + std::to_string(row.size()) + " fields, the header " +
             std::to_string(table.header.size());
    line(row);
  }
  out.flush();
  return out ? std::string() : "cannot write " + path;
}

}  // namespace benchcsv
