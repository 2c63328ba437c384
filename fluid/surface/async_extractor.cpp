#include "fluid/surface/async_extractor.hpp"

namespace fluid {

namespace {

template <class T>
void copyInto(std::vector<T>& to, std::span<const T> from) {
  to.assign(from.begin(), from.end());
}

}  // namespace

AsyncSurfaceExtractor::AsyncSurfaceExtractor() : worker_([this] { work(); }) {}

AsyncSurfaceExtractor::~AsyncSurfaceExtractor() {
  {
    const std::lock_guard lock(mutex_);
    quit_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

void AsyncSurfaceExtractor::start(const SurfaceInput& input, const SurfaceParams& params) {
  if (pending_) {  // the worker may still read the copy below: wait for it, drop its mesh
    std::unique_lock lock(mutex_);
    wake_.wait(lock, [this] { return job_done_; });
    job_done_ = false;
    pending_ = false;
  }
  // The worker is idle (waiting for job_ready_): the copy is ours until we publish it.
  copyInto(x_, input.x);
  copyInto(y_, input.y);
  copyInto(z_, input.z);
  copyInto(strength_, input.strength);
  copyInto(radius_scale_, input.radiusScale);
  copyInto(user_, input.user);
  params_ = params;
  {
    const std::lock_guard lock(mutex_);
    job_ready_ = true;
  }
  pending_ = true;
  wake_.notify_all();
}

SurfaceStatus AsyncSurfaceExtractor::collect(SurfaceMesh& out) {
  if (!pending_) return {"AsyncSurfaceExtractor::collect: no extraction was started"};
  std::unique_lock lock(mutex_);
  wake_.wait(lock, [this] { return job_done_; });
  job_done_ = false;
  pending_ = false;
  std::swap(out, mesh_);
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
    const SurfaceInput input{x_, y_, z_, strength_, radius_scale_, user_};
    status_ = extractor_.extract(input, params_, mesh_);
    {
      const std::lock_guard lock(mutex_);
      job_done_ = true;
    }
    wake_.notify_all();
  }
}

}  // namespace fluid
