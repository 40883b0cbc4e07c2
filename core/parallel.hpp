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
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace sc {

// Runs fn(i, progress) for every i < k on `threads` threads, taking the
// next i as each finishes, while this thread reports progress (from + (to
// - from) times the share of the work done, the ticks of the i under way
// included; i weighs weight[i] where weights are given, else as much as
// any other) and watches for a cancel: a cancel, or an error on any
// thread, stops the others at their next progress tick, and is rethrown
// here once they have all stopped. fn must not touch what another i
// writes; the result then does not depend on the threads.
template <class F>
void run_parallel(size_t k, unsigned threads, Progress &progress, F &&fn,
                  double from = 0, double to = 1,
                  const std::vector<double> *weight = nullptr) {
  std::atomic<size_t> next{0}, done{0};
  std::atomic<int> stop{0};
  std::exception_ptr error;
  std::mutex mu;
  std::condition_variable cv;
  auto weight_of = [&](size_t i) { return weight ? (*weight)[i] : 1.0; };
  double total = 0;
  for (size_t i = 0; i < k; ++i)
    total += weight_of(i);
  // Per thread: the i under way (k for none) and the fraction its ticks
  // have reached; and the weight of the i done.
  struct Slot {
    std::atomic<int> *stop;
    std::atomic<size_t> i;
    std::atomic<double> fraction{0};
  };
  threads = unsigned(std::max<size_t>(1, std::min<size_t>(threads, k)));
  std::vector<Slot> slots(threads);
  double done_weight = 0; // under mu
  auto worker = [&](Slot &slot) {
    for (;;) {
      const size_t i = next++;
      if (i >= k || stop.load())
        break;
      slot.fraction = 0;
      slot.i = i;
      try {
        Progress mine(
            [](void *u, sc_stage_t, double f) {
              Slot &s = *static_cast<Slot *>(u);
              s.fraction = f;
              return s.stop->load();
            },
            &slot);
        fn(i, mine);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        if (!error)
          error = std::current_exception();
        stop = 1;
      }
      {
        std::lock_guard<std::mutex> lock(mu);
        slot.i = k;
        done_weight += weight_of(i);
        ++done;
      }
      cv.notify_all();
    }
  };
  for (Slot &s : slots) {
    s.stop = &stop;
    s.i = k;
  }
  std::vector<std::thread> pool;
  pool.reserve(threads);
  std::exception_ptr cancelled;
  try {
    for (unsigned t = 0; t < threads; ++t)
      pool.emplace_back(worker, std::ref(slots[t]));
    std::unique_lock<std::mutex> lock(mu);
    while (done.load() < k && !stop.load()) {
      cv.wait_for(lock, std::chrono::milliseconds(50));
      double w = done_weight;
      for (const Slot &s : slots) {
        const size_t i = s.i;
        if (i < k)
          w += weight_of(i) * std::min(1.0, s.fraction.load());
      }
      lock.unlock();
      progress.report(from + (to - from) * (total > 0 ? w / total : 0));
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
// thread, run as run_parallel() runs them, progress going from `from` to
// `to` as they end. body must not touch what another slice writes; the
// result then does not depend on the threads.
template <class F>
void run_sliced(size_t count, unsigned threads, bool parallel,
                Progress &progress, F &&body, double from, double to) {
  if (threads < 2 || !parallel) {
    progress.report(from);
    body(size_t(0), count);
    progress.report(to);
    return;
  }
  const size_t k = 4 * size_t(threads);
  run_parallel(
      k, threads, progress,
      [&](size_t i, Progress &) { body(count * i / k, count * (i + 1) / k); },
      from, to);
}

} // namespace sc

#endif
