// render — running independent pieces of work on the worker threads: the film's rows and
// strips, and the files a scene reads.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace cmam::render {

/// The threads a parallel_range will run on (`threads` 0: all cores).
inline int worker_count(int threads) {
#ifdef CMAM_STD_THREADS
    return std::max(1,
                    threads > 0 ? threads : static_cast<int>(std::thread::hardware_concurrency()));
#else
    return threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
#endif
}

/// body(begin, end) over [0, n) in parallel: with oneTBB, or, in a build for ThreadSanitizer
/// (CMAM_STD_THREADS), with std::thread workers taking one index at a time, whose hand-offs
/// ThreadSanitizer sees (it cannot see into an uninstrumented oneTBB). With oneTBB, `threads`
/// bounds the workers only under a tbb::global_control the caller holds (the film's) or in
/// parallel_range_on.
template <class Body>
void parallel_range(int n, int threads, Body&& body) {
#ifdef CMAM_STD_THREADS
    const int workers = worker_count(threads);
    std::atomic<int> next{0};
    std::vector<std::thread> pool;
    for (int w = 0; w < workers; ++w)
        pool.emplace_back([&] {
            for (int i = next++; i < n; i = next++) body(i, i + 1);
        });
    for (std::thread& t : pool) t.join();
#else
    (void)threads;
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 1),
                      [&](const tbb::blocked_range<int>& r) { body(r.begin(), r.end()); });
#endif
}

/// parallel_range on at most `threads` workers (0: all cores) whoever calls it.
template <class Body>
void parallel_range_on(int n, int threads, Body&& body) {
#ifndef CMAM_STD_THREADS
    if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute([&] { parallel_range(n, threads, body); });
        return;
    }
#endif
    parallel_range(n, threads, body);
}

/// Tasks 0..n-1 in waves of at most `wave` tasks: body(first, begin, end) runs tasks
/// first + begin .. first + end - 1 in parallel (begin and end count within the wave), then
/// after_wave(first, count) runs on the calling thread. What the tasks write per task and
/// after_wave adds up in task order is the same for any thread count.
template <class Body, class AfterWave>
void in_waves(uint64_t n, int wave, int threads, Body&& body, AfterWave&& after_wave) {
    for (uint64_t first = 0; first < n; first += uint64_t(wave)) {
        const int count = static_cast<int>(std::min<uint64_t>(uint64_t(wave), n - first));
        parallel_range(count, threads, [&](int begin, int end) { body(first, begin, end); });
        after_wave(first, count);
    }
}

}  // namespace cmam::render
