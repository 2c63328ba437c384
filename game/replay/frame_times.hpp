#pragma once
// Per-frame timing rows of a replay: the CSV `fluiddemo replay --csv` writes (and
// scripts/plot_frame_times.py draws), percentiles per phase, and the B/A comparison of two runs.
//
// CSV columns, one row per rendered frame:
//   frame,step,input_ms,physics_ms,fluid_ms,meshing_ms,render_ms,ui_ms,frame_ms,particles,sprites,triangles,
//   mesh_worker_ms,sph_steps,density_err_mean,density_err_max,pushed_out,push_depth_mm,speed_clamps,
//   dt_min_clamps,dt_request_cuts,nonfinite,warned,state_hash
// step is the simulation step count after the frame; particles the SPH particles, sprites the CPU
// sprite particles, triangles the meshed surfaces' (water and blob); mesh_worker_ms the time the
// asynchronous meshing's worker spent on the surfaces drawn (meshing_ms is then only the main thread's
// wait and hand-over; 0 when meshing is synchronous); sph_steps .. nonfinite the SPH solver's health
// counters over the frame's sub-steps (FrameTruth); warned is 1 where the overlay's plot draws a
// red marker; state_hash is empty except on checkpoint steps.

#include "engine/profile/profiler.hpp"

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace game {

// The SPH solver's health over one frame (fluid::SphStepTotals of its steps), as the CSV has it.
struct FrameTruth {
  std::uint64_t sph_steps = 0;
  double density_err_mean = 0.0;  // mean over the sub-steps of the mean max(0, rho/rho_0 - 1)
  double density_err_p99 = 0.0;  // the largest over the sub-steps of the 99th percentile over particles
  double density_err_max = 0.0;
  std::uint64_t pushed_out = 0;  // particles pushed out of colliders
  double push_depth_mm = 0.0;    // the deepest of them (mm)
  std::uint64_t speed_clamps = 0;
  std::uint64_t dt_min_clamps = 0;
  std::uint64_t dt_request_cuts = 0;
  std::uint64_t nonfinite = 0;
  bool warned = false;  // a warning counter fired (the overlay's red marker)
};

struct FrameRow {
  int frame = 0;
  std::uint64_t step = 0;
  std::array<double, engine::kPhaseCount> phase_ms{};
  double frame_ms = 0.0;
  std::uint64_t particles = 0;  // all the water: the SPH store and the pump
  // Where it is (game::waterWhereabouts): pool, jet and air, ground, pump.
  std::uint64_t water_pool = 0, water_air = 0, water_ground = 0, water_pump = 0;
  std::uint64_t water_spray = 0;  // of the water above, flying ballistic (fluid::SphParams::spray_speed)
  std::uint64_t blasts = 0;       // explosives that went off in this step
  std::uint64_t sprites = 0;
  std::uint64_t triangles = 0;
  double mesh_worker_ms = 0.0;
  FrameTruth truth;
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
