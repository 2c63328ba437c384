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
  line +=
      ",particles,water_pool,water_air,water_ground,water_pump,water_spray,blasts,sprites,triangles,mesh_worker_ms,sph_steps,density_err_"
      "mean,density_err_p99,density_err_max,pushed_"
      "out,push_depth_mm,speed_clamps,"
      "dt_min_clamps,dt_request_cuts,nonfinite,warned,state_hash";
  return line;
}

std::string frameCsvRow(const FrameRow& row) {
  char number[64];
  std::string line = std::to_string(row.frame) + "," + std::to_string(row.step);
  for (int p = 0; p <= engine::kPhaseCount; ++p) {
    std::snprintf(number, sizeof number, ",%.4f", p == engine::kPhaseCount ? row.frame_ms : row.phase_ms[p]);
    line += number;
  }
  for (std::uint64_t count :
       {row.particles, row.water_pool, row.water_air, row.water_ground, row.water_pump, row.water_spray, row.blasts,
        row.sprites, row.triangles}) {
    line += ',';
    line += std::to_string(count);
  }
  std::snprintf(number, sizeof number, ",%.4f", row.mesh_worker_ms);
  line += number;
  line += ',' + std::to_string(row.truth.sph_steps);
  const FrameTruth& t = row.truth;
  // %.9g: a float's value survives the text round trip.
  std::snprintf(number, sizeof number, ",%.9g,%.9g,%.9g", t.density_err_mean, t.density_err_p99, t.density_err_max);
  line += number;
  line += ',' + std::to_string(t.pushed_out);
  std::snprintf(number, sizeof number, ",%.6g", t.push_depth_mm);
  line += number;
  for (std::uint64_t count : {t.speed_clamps, t.dt_min_clamps, t.dt_request_cuts, t.nonfinite}) {
    line += ',';
    line += std::to_string(count);
  }
  line += t.warned ? ",1," : ",0,";
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
    if (ok)
      ok = parseCell(cells[++c], row.particles) && parseCell(cells[++c], row.water_pool) &&
           parseCell(cells[++c], row.water_air) && parseCell(cells[++c], row.water_ground) &&
           parseCell(cells[++c], row.water_pump) && parseCell(cells[++c], row.water_spray) &&
           parseCell(cells[++c], row.blasts) && parseCell(cells[++c], row.sprites) &&
           parseCell(cells[++c], row.triangles) && parseCell(cells[++c], row.mesh_worker_ms);
    FrameTruth& t = row.truth;
    if (ok)
      ok = parseCell(cells[++c], t.sph_steps) && parseCell(cells[++c], t.density_err_mean) &&
           parseCell(cells[++c], t.density_err_p99) && parseCell(cells[++c], t.density_err_max) &&
           parseCell(cells[++c], t.pushed_out) && parseCell(cells[++c], t.push_depth_mm) &&
           parseCell(cells[++c], t.speed_clamps) && parseCell(cells[++c], t.dt_min_clamps) &&
           parseCell(cells[++c], t.dt_request_cuts) && parseCell(cells[++c], t.nonfinite);
    if (ok) {
      int warned = 0;
      ok = parseCell(cells[++c], warned) && (warned == 0 || warned == 1);
      t.warned = warned == 1;
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
