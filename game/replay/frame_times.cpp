// Frame timing rows, CSV and percentiles (frame_times.hpp).
#include "game/replay/frame_times.hpp"

#include "game/replay/replay_file.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>

namespace game {

std::string columnName(int index) {
  if (index == engine::kPhaseCount) return "frame";
  return std::string(engine::phaseName(static_cast<engine::Phase>(index)));
}

std::string frameCsvHeader() {
  std::string line = "frame,step";
  for (int p = 0; p <= engine::kPhaseCount; ++p) {
    line += ',';
    line += columnName(p);
    line += "_ms";
  }
  for (const ColumnSpec& column : frameColumnCatalogue()) {
    line += ',';
    line += column.name;
  }
  line += ",state_hash";
  return line;
}

namespace {

void appendCell(std::string& line, const ColumnSpec& column, double value) {
  char number[64];
  switch (column.format) {
    case ColumnFormat::count:
      std::snprintf(number, sizeof number, ",%llu", static_cast<unsigned long long>(std::llround(value)));
      break;
    case ColumnFormat::flag:
      std::snprintf(number, sizeof number, ",%d", value != 0.0 ? 1 : 0);
      break;
    case ColumnFormat::milliseconds:
      std::snprintf(number, sizeof number, ",%.4f", value);
      break;
    case ColumnFormat::ratio:  // %.9g: a float's value survives the text round trip
      std::snprintf(number, sizeof number, ",%.9g", value);
      break;
    case ColumnFormat::millimetres:
      std::snprintf(number, sizeof number, ",%.6g", value);
      break;
  }
  line += number;
}

}  // namespace

std::string frameCsvRow(const FrameRow& row) {
  char number[64];
  std::string line = std::to_string(row.frame) + "," + std::to_string(row.step);
  for (int p = 0; p <= engine::kPhaseCount; ++p) {
    std::snprintf(number, sizeof number, ",%.4f", p == engine::kPhaseCount ? row.frame_ms : row.phase_ms[p]);
    line += number;
  }
  const std::span<const ColumnSpec> columns = frameColumnCatalogue();
  for (std::size_t c = 0; c < columns.size(); ++c) appendCell(line, columns[c], row.columns.values[c]);
  line += ',';
  if (row.has_hash) line += hashHex(row.state_hash);
  return line;
}

bool writeFrameCsv(const std::filesystem::path& path, const std::vector<FrameRow>& rows, std::string& error) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) {
    error = path.string() + ": cannot write: " + std::strerror(errno);
    return false;
  }
  out << frameCsvHeader() << '\n';
  for (const FrameRow& row : rows) out << frameCsvRow(row) << '\n';
  out.flush();
  if (!out) {
    error = path.string() + ": write error";
    return false;
  }
  return true;
}

namespace {

std::vector<std::string_view> splitCommas(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

template <typename T>
bool parseCell(std::string_view cell, T& out, int base = 10) {
  std::from_chars_result r{};
  if constexpr (std::is_floating_point_v<T>) {
    r = std::from_chars(cell.data(), cell.data() + cell.size(), out);
    if (r.ec == std::errc() && !std::isfinite(out)) return false;
  } else {
    r = std::from_chars(cell.data(), cell.data() + cell.size(), out, base);
  }
  return r.ec == std::errc() && r.ptr == cell.data() + cell.size() && !cell.empty();
}

}  // namespace

bool readFrameCsv(const std::filesystem::path& path, std::vector<FrameRow>& rows, std::string& error) {
  rows.clear();
  std::string text;
  if (!readTextFile(path, text, error)) return false;
  const std::string label = path.string();
  std::size_t pos = 0;
  int line_number = 0;
  const std::string header_line = frameCsvHeader();
  const std::vector<std::string_view> expected = splitCommas(header_line);
  std::vector<std::string> header(expected.begin(), expected.end());
  while (pos < text.size()) {
    std::size_t newline = text.find('\n', pos);
    if (newline == std::string::npos) newline = text.size();
    std::string_view line(text.data() + pos, newline - pos);
    pos = newline + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line_number == 1) {
      if (line != header_line) {
        error = label + ":1: header is not '" + header_line + "' (not a fluiddemo replay CSV?)";
        return false;
      }
      continue;
    }
    if (line.empty()) continue;
    const std::vector<std::string_view> cells = splitCommas(line);
    const auto where = [&](std::size_t column) {
      return label + ":" + std::to_string(line_number) + ": column '" + header[std::min(column, header.size() - 1)] +
             "': ";
    };
    if (cells.size() != header.size()) {
      error = where(cells.size()) + "expected " + std::to_string(header.size()) + " cells, got " +
              std::to_string(cells.size());
      return false;
    }
    FrameRow row;
    std::size_t c = 0;
    bool ok = parseCell(cells[c], row.frame) && parseCell(cells[++c], row.step);
    for (int p = 0; ok && p <= engine::kPhaseCount; ++p)
      ok = parseCell(cells[++c], p == engine::kPhaseCount ? row.frame_ms : row.phase_ms[p]);
    const std::span<const ColumnSpec> columns = frameColumnCatalogue();
    for (std::size_t k = 0; ok && k < columns.size(); ++k) {
      double& value = row.columns.values[k];
      ok = parseCell(cells[++c], value);
      if (ok && columns[k].format == ColumnFormat::flag) ok = value == 0.0 || value == 1.0;
      if (ok && columns[k].format == ColumnFormat::count) ok = value >= 0.0 && value == std::floor(value);
    }
    if (ok && !cells[++c].empty()) ok = row.has_hash = parseCell(cells[c], row.state_hash, 16);
    if (!ok) {
      error = where(c) + "bad value '" + std::string(cells[c].substr(0, 40)) + "'";
      return false;
    }
    rows.push_back(row);
  }
  if (line_number == 0) {
    error = label + ": empty file (expected the replay CSV header)";
    return false;
  }
  return true;
}

Percentiles percentiles(const std::vector<double>& values, std::vector<double>& scratch) {
  Percentiles out;
  if (values.empty()) return out;
  scratch = values;
  std::sort(scratch.begin(), scratch.end());
  // Nearest rank: the smallest value with at least q of the samples at or below it.
  const auto rank = [&](double q) {
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(scratch.size())));
    return scratch[std::clamp<std::size_t>(k, 1, scratch.size()) - 1];
  };
  out.p50 = rank(0.50);
  out.p95 = rank(0.95);
  out.p99 = rank(0.99);
  out.max = scratch.back();
  return out;
}

std::array<Percentiles, engine::kPhaseCount + 1> phasePercentiles(const std::vector<FrameRow>& rows) {
  std::array<Percentiles, engine::kPhaseCount + 1> out{};
  std::vector<double> values, scratch;
  values.reserve(rows.size());
  for (int p = 0; p <= engine::kPhaseCount; ++p) {
    values.clear();
    for (const FrameRow& row : rows) values.push_back(p == engine::kPhaseCount ? row.frame_ms : row.phase_ms[p]);
    out[p] = percentiles(values, scratch);
  }
  return out;
}

void printPercentileTable(std::FILE* out, const std::vector<FrameRow>& rows) {
  const auto table = phasePercentiles(rows);
  std::fprintf(out, "%-10s %10s %10s %10s %10s   (%zu frames)\n", "phase", "p50 ms", "p95 ms", "p99 ms", "max ms",
               rows.size());
  for (int p = 0; p <= engine::kPhaseCount; ++p) {
    std::fprintf(out, "%-10s %10.3f %10.3f %10.3f %10.3f\n", columnName(p).c_str(), table[p].p50, table[p].p95,
                 table[p].p99, table[p].max);
  }
}

void printComparison(std::FILE* out, const std::string& label_a, const std::vector<FrameRow>& a,
                     const std::string& label_b, const std::vector<FrameRow>& b) {
  const auto ta = phasePercentiles(a);
  const auto tb = phasePercentiles(b);
  std::fprintf(out, "A: %s (%zu frames)\nB: %s (%zu frames)\n", label_a.c_str(), a.size(), label_b.c_str(), b.size());
  std::fprintf(out, "%-10s %10s %10s %8s %10s %10s %8s\n", "phase", "A p50 ms", "B p50 ms", "B/A", "A p95 ms",
               "B p95 ms", "B/A");
  const auto ratio = [](double x, double y) { return x > 0.0 ? y / x : std::nan(""); };
  for (int p = 0; p <= engine::kPhaseCount; ++p) {
    std::fprintf(out, "%-10s %10.3f %10.3f %8.3f %10.3f %10.3f %8.3f\n", columnName(p).c_str(), ta[p].p50, tb[p].p50,
                 ratio(ta[p].p50, tb[p].p50), ta[p].p95, tb[p].p95, ratio(ta[p].p95, tb[p].p95));
  }
}

}  // namespace game
