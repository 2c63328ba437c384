#pragma once
// The data-parallel loops of the fluid library: tbb::parallel_for, tbb::parallel_reduce and
// tbb::parallel_deterministic_reduce with their own signatures, so call sites read as oneTBB.
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
#include <tbb/blocked_range.h>

#if defined(__SANITIZE_THREAD__)
#include <thread>
#else
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#endif

namespace fluid::par {

template <class Value>
using Range = tbb::blocked_range<Value>;

#if defined(__SANITIZE_THREAD__)
namespace detail {
// Levels of the halving that fork a thread (2^2 = up to four ranges run at once).
constexpr int kForkLevels = 2;

template <class Value, class Body>
void forRange(const Range<Value>& r, const Body& body, int level) {
  if (!r.is_divisible()) {
    body(r);
    return;
  }
  Range<Value> left = r;
  const Range<Value> right(left, tbb::split());  // left keeps [begin, middle)
  if (level < kForkLevels) {
    std::thread t([&] { forRange(right, body, level + 1); });
    forRange(left, body, level + 1);
    t.join();
  } else {
    forRange(left, body, level + 1);
    forRange(right, body, level + 1);
  }
}

template <class Value, class T, class Body, class Join>
T reduceRange(const Range<Value>& r, const T& identity, const Body& body, const Join& join, int level) {
  if (!r.is_divisible()) return body(r, identity);
  Range<Value> left = r;
  const Range<Value> right(left, tbb::split());
  if (level < kForkLevels) {
    T right_value = identity;
    std::thread t([&] { right_value = reduceRange(right, identity, body, join, level + 1); });
    const T left_value = reduceRange(left, identity, body, join, level + 1);
    t.join();
    return join(left_value, right_value);
  }
  const T left_value = reduceRange(left, identity, body, join, level + 1);
  return join(left_value, reduceRange(right, identity, body, join, level + 1));
}
}  // namespace detail

template <class Value, class Body>
void parallel_for(const Range<Value>& r, const Body& body) {
  if (!r.empty()) detail::forRange(r, body, 0);
}
template <class Value, class T, class Body, class Join>
T parallel_deterministic_reduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return r.empty() ? identity : detail::reduceRange(r, identity, body, join, 0);
}
template <class Value, class T, class Body, class Join>
T parallel_reduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return parallel_deterministic_reduce(r, identity, body, join);
}
#else
template <class Value, class Body>
void parallel_for(const Range<Value>& r, const Body& body) {
  tbb::parallel_for(r, body);
}
template <class Value, class T, class Body, class Join>
T parallel_deterministic_reduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return tbb::parallel_deterministic_reduce(r, identity, body, join);
}
template <class Value, class T, class Body, class Join>
T parallel_reduce(const Range<Value>& r, const T& identity, const Body& body, const Join& join) {
  return tbb::parallel_reduce(r, identity, body, join);
}
#endif

}  // namespace fluid::par
