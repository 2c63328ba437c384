#include "fluid/surface/async_extractor.hpp"

#include "fluid/core/parallel.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>

namespace fluid {

namespace {

template <class T>
void copyInto(std::vector<T>& to, std::span<const T> from) {
  to.assign(from.begin(), from.end());
}

}  // namespace

int asyncMeshSlots(int threads) {
  if (threads > 0) return threads;
  return std::max(1, static_cast<int>(par::allowedThreads() / 2));
}

AsyncSurfaceExtractor::AsyncSurfaceExtractor(int threads)
    : arena_(asyncMeshSlots(threads)), worker_([this] { work(); }) {}

AsyncSurfaceExtractor::~AsyncSurfaceExtractor() {
  {
    const std::lock_guard lock(mutex_);
    quit_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

void AsyncSurfaceExtractor::waitForPending() {
  if (!pending_) return;
  std::unique_lock lock(mutex_);
  wake_.wait(lock, [this] { return job_done_; });
  job_done_ = false;
  pending_ = false;
}

void AsyncSurfaceExtractor::launch(Job job) {
  // The worker is idle (waiting for job_ready_): job_ and the copies are ours until published.
  job_ = std::move(job);
  {
    const std::lock_guard lock(mutex_);
    job_ready_ = true;
  }
  pending_ = true;
  wake_.notify_all();
}

void AsyncSurfaceExtractor::start(const SurfaceInput& input, const SurfaceParams& params) {
  waitForPending();  // the worker may still read the copy below
  const PointView& from = input.positions;
  positions_.resize(from.count);
  if (from.stride == sizeof(glm::vec3) && from.count > 0)  // packed: the layout the copy keeps
    std::memcpy(positions_.data(), from.data, from.count * sizeof(glm::vec3));
  else
    for (std::size_t i = 0; i < from.count; ++i) positions_[i] = from[i];
  copyInto(strength_, input.strength);
  copyInto(radius_scale_, input.radiusScale);
  copyInto(user_, input.user);
  copyInto(stretch_, input.stretch);
  params_ = params;
  launch([this](SurfaceExtractor& extractor, SurfaceMesh& mesh) {
    const SurfaceInput copy{pointView(positions_), strength_, radius_scale_, user_, stretch_};
    return extractor.extract(copy, params_, mesh);
  });
}

void AsyncSurfaceExtractor::startJob(Job job) {
  waitForPending();
  launch(std::move(job));
}

SurfaceStatus AsyncSurfaceExtractor::collect(SurfaceMesh& out) {
  if (!pending_) return {"AsyncSurfaceExtractor::collect: no extraction was started"};
  std::unique_lock lock(mutex_);
  wake_.wait(lock, [this] { return job_done_; });
  job_done_ = false;
  pending_ = false;
  std::swap(out, mesh_);
  last_job_ms_ = job_ms_;
  return status_;
}

void AsyncSurfaceExtractor::work() {
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return job_ready_ || quit_; });
      if (!job_ready_) return;  // quit with no job left
      job_ready_ = false;
    }
    const auto begin = std::chrono::steady_clock::now();
    arena_.execute([this] { status_ = job_(extractor_, mesh_); });
    job_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    {
      const std::lock_guard lock(mutex_);
      job_done_ = true;
    }
    wake_.notify_all();
  }
}

}  // namespace fluid
