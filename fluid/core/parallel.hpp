#pragma once
// The data-parallel loops of the fluid library: parallelFor, parallelReduce and
// parallelDeterministicReduce take the arguments of their oneTBB namesakes (tbb::parallel_for, ...).
//
// Why not call oneTBB directly: ThreadSanitizer cannot see the synchronisation inside the
// uninstrumented system oneTBB and reports every hand-over between a worker and the caller as a
// race. In TSan builds these run the same recursive halving of the range on plain std::threads
// (fork at the top levels, join before returning), which TSan understands, so a TSan run of the
// unit tests checks our code rather than drowning in reports about the library.
//
// Both paths split a blocked_range exactly as oneTBB's simple partitioner does for the
// deterministic reduce (halve while size > grain, left half first) and join left with right, so
// deterministic reductions give the same bits in TSan builds as in normal ones.
//
// Thread cap: both paths run a loop's body on at most min(N, slots) threads at once, N being
// oneTBB's max_allowed_parallelism (the smallest live tbb::global_control, as `fluiddemo
// simulate --threads N` and the thread-count tests set it; default: the number of cores) and
// slots the caller's task arena's (the core count unless inside a tbb::task_arena). oneTBB
// does that itself; the TSan path reads the same two values and also stops at
// detail::kMaxThreads.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstddef>

#if defined(__SANITIZE_THREAD__)
#include <thread>
#else
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#endif

namespace fluid::par {

template <class Value>
using Range = tbb::blocked_range<Value>;

// Threads a loop started from this thread may run on, as oneTBB runs it: the active
// max_allowed_parallelism, at most the slots of the caller's arena (the core count in the implicit
// arena, N inside a tbb::task_arena(N).execute, as the depth-map bake and batch queries use). Only
// reads values inside libtbb; no oneTBB task or thread is involved.
inline std::size_t allowedThreads() {
  const std::size_t allowed = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  const auto slots = static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  return std::max<std::size_t>(1, std::min(allowed, slots));
}

#if defined(__SANITIZE_THREAD__)
namespace detail {
// Most threads one loop runs on at once (the caller's included): each loop starts its own
// threads, which is slow under TSan, and four already exercise every hand-over.
constexpr std::size_t kMaxThreads = 4;

// Threads a loop may use: allowedThreads(), as oneTBB would run it, and here also at most kMaxThreads.
inline std::size_t threadBudget() { return std::min(allowedThreads(), kMaxThreads); }

// `threads` is how many threads this subrange may occupy (this one included): a split hands the
// right half threads / 2 of them on a new thread and keeps the rest, so at most `threads` run at
// once. Forking never changes how the range is split, only which thread runs a piece.
template <class Value, class Body>
void forRange(const Range<Value>& r, const Body& body, std::size_t threads) {
  if (!r.is_divisible()) {
    body(r);
    return;
  }
  Range<Value> left = r;
  const Range<Value> right(left, tbb::split());  // left keeps [begin, middle)
  if (threads > 1) {
    const std::size_t right_threads = threads / 2;
    std::thread t([&] { forRange(right, body, right_threads); });
    forRange(left, body, threads - right_threads);
    t.join();
  } else {
    forRange(left, body, 1);
    forRange(right, body, 1);
  }
}

template <class Value, class T, class Body, class Join>
T reduceRange(const Range<Value>& r, const T& identity, const Body& body, const Join& join, std::size_t threads) {
  if (!r.is_divisible()) return body(r, identity);
  Range<Value> left = r;
  const Range<Value> right(left, tbb::split());
  if (threads > 1) {
    const std::size_t right_threads = threads / 2;
    T right_value = identity;
    std::thread t([&] { right_value = reduceRange(right, identity, body, join, right_threads); });
    const T left_value = reduceRange(left, identity, body, join, threads - right_threads);
    t.join();
    return join(left_value, right_value);
  }
  const T left_value = reduceRange(left, identity, body, join, 1);
  return join(left_value, reduceRange(right, identity, body, join, 1));
}
}  // namespace detail

template <class Value, class Body>
void parallelFor(const Range<Value>& r, const Body& body) {
  if (!r.empty()) detail::forRange(r, body, detail::threadBudget());
}
template <class Value, class T, class Body, class Join>
T parallelDeterministicReduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return r.empty() ? identity : detail::reduceRange(r, identity, body, join, detail::threadBudget());
}
template <class Value, class T, class Body, class Join>
T parallelReduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return parallelDeterministicReduce(r, identity, body, join);
}
#else
template <class Value, class Body>
void parallelFor(const Range<Value>& r, const Body& body) {
  tbb::parallel_for(r, body);
}
template <class Value, class T, class Body, class Join>
T parallelDeterministicReduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return tbb::parallel_deterministic_reduce(r, identity, body, join);
}
template <class Value, class T, class Body, class Join>
T parallelReduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return tbb::parallel_reduce(r, identity, body, join);
}
#endif

}  // namespace fluid::par
