// Work spread over threads, with progress and cancel on the calling
// thread. Internal to core/.
//
// SPDX-License-Identifier: GPL-3.0-or-later
#ifndef SC_CORE_PARALLEL_HPP
#define SC_CORE_PARALLEL_HPP

#include "internal.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace sc {

// Runs fn(i, progress) for every i < k on `threads` threads, taking the
// next i as each finishes, while this thread reports progress (from + (to
// - from) times the share of i done) and watches for a cancel: a cancel,
// or an error on any thread, stops the others at their next progress tick,
// and is rethrown here once they have all stopped. fn must not touch what
// another i writes; the result then does not depend on the threads.
template <class F>
void run_parallel(size_t k, unsigned threads, Progress &progress, F &&fn,
                  double from = 0, double to = 1) {
  std::atomic<size_t> next{0}, done{0};
  std::atomic<int> stop{0};
  std::exception_ptr error;
  std::mutex mu;
  std::condition_variable cv;
  auto worker = [&] {
    Progress mine(
        [](void *u, sc_stage_t, double) {
          return static_cast<std::atomic<int> *>(u)->load();
        },
        &stop);
    for (;;) {
      const size_t i = next++;
      if (i >= k || stop.load())
        break;
      try {
        fn(i, mine);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        if (!error)
          error = std::current_exception();
        stop = 1;
      }
      {
        std::lock_guard<std::mutex> lock(mu);
        ++done;
      }
      cv.notify_all();
    }
  };
  threads = unsigned(std::max<size_t>(1, std::min<size_t>(threads, k)));
  std::vector<std::thread> pool;
  pool.reserve(threads);
  std::exception_ptr cancelled;
  try {
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back(worker);
    std::unique_lock<std::mutex> lock(mu);
    while (done.load() < k && !stop.load()) {
      cv.wait_for(lock, std::chrono::milliseconds(50));
      lock.unlock();
      progress.report(from + (to - from) * double(done.load()) / double(k));
      lock.lock();
    }
    lock.unlock();
    if (!stop.load())
      progress.report(to); // however fast the work went
  } catch (...) {
    cancelled = std::current_exception();
    stop = 1;
  }
  for (std::thread &t : pool)
    t.join();
  if (cancelled)
    std::rethrow_exception(cancelled);
  if (error)
    std::rethrow_exception(error);
}

// Runs body(b, e) over slices [b, e) that cover [0, count): one slice
// where `parallel` is false or there is one thread, else about four a
// thread, run as run_parallel() runs them (progress stays at `at`). body
// must not touch what another slice writes; the result then does not
// depend on the threads.
template <class F>
void run_sliced(size_t count, unsigned threads, bool parallel,
                Progress &progress, F &&body, double at) {
  if (threads < 2 || !parallel) {
    body(size_t(0), count);
    return;
  }
  const size_t k = 4 * size_t(threads);
  run_parallel(
      k, threads, progress,
      [&](size_t i, Progress &) { body(count * i / k, count * (i + 1) / k); },
      at, at);
}

} // namespace sc

#endif
