#pragma once
// Per-frame timing rows of a replay: the CSV `fluiddemo replay --csv` writes (and
// scripts/plot_frame_times.py draws), percentiles per phase, and the B/A comparison of two runs.
//
// CSV columns, one row per rendered frame:
//   frame,step,input_ms,..,ui_ms,frame_ms, then every effect's columns (frameColumnCatalogue(): the
//   columns each effect's file declares, in registry order; 0 where the scene does not list the
//   effect), then state_hash (empty except on checkpoint steps). `fluiddemo scene-keys --columns`
//   lists them with their docs (docs/replay.md).

#include "engine/profile/profiler.hpp"
#include "game/effects/effect_report.hpp"

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace game {

struct FrameRow {
  int frame = 0;
  std::uint64_t step = 0;
  std::array<double, engine::kPhaseCount> phase_ms{};
  double frame_ms = 0.0;
  FrameColumns columns;  // the effects' columns (Effect::reportColumns)
  bool has_hash = false;
  std::uint64_t state_hash = 0;
};

// The header line (no newline) and one row.
std::string frameCsvHeader();
std::string frameCsvRow(const FrameRow& row);
// Writes header + rows. False + message naming the path on failure.
bool writeFrameCsv(const std::filesystem::path& path, const std::vector<FrameRow>& rows, std::string& error);
// Reads a CSV written by writeFrameCsv. False + "FILE:LINE: column 'C': ..." on bad content.
bool readFrameCsv(const std::filesystem::path& path, std::vector<FrameRow>& rows, std::string& error);

struct Percentiles {
  double p50 = 0.0, p95 = 0.0, p99 = 0.0, max = 0.0;
};
// Nearest-rank percentiles of `values` (sorted copy kept in `scratch`); all zero when empty.
Percentiles percentiles(const std::vector<double>& values, std::vector<double>& scratch);

// Per-phase (and whole-frame) percentiles over rows; index kPhaseCount is the frame total.
std::array<Percentiles, engine::kPhaseCount + 1> phasePercentiles(const std::vector<FrameRow>& rows);

// "input".."ui", then "frame" for index kPhaseCount.
std::string columnName(int index);

// Prints the p50/p95/p99/max table per phase and frame.
void printPercentileTable(std::FILE* out, const std::vector<FrameRow>& rows);

// Prints per-phase p50 and p95 of A and B and the ratios B/A.
void printComparison(std::FILE* out, const std::string& label_a, const std::vector<FrameRow>& a,
                     const std::string& label_b, const std::vector<FrameRow>& b);

}  // namespace game
