// Parallel loop over the film in 16x16 tiles. Each pixel is visited by exactly one task, so per-pixel results
// do not depend on scheduling or the thread count.
#pragma once
#include "core/interrupt.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <functional>
#include <mutex>

namespace penumbra {

// body(x0, y0, x1, y1) handles the tile [x0,x1) x [y0,y1); progress(fraction) is serialized.
template <typename Body>
void for_each_tile(int width, int height, int threads, const Body& body,
                   const std::function<void(float)>& progress = nullptr) {
    constexpr int tile = 16;
    const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    std::atomic<int> done{0};
    std::mutex progress_mutex;
    tbb::task_arena arena(threads > 0 ? threads : tbb::this_task_arena::max_concurrency());
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const tbb::blocked_range2d<int>& r) {
            for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
                for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) {
                    check_interrupt();
                    body(tx * tile, ty * tile, std::min(width, (tx + 1) * tile), std::min(height, (ty + 1) * tile));
                    const int finished = ++done;
                    if (progress) {
                        std::lock_guard<std::mutex> lock(progress_mutex);
                        progress(float(finished) / float(tiles_x * tiles_y));
                    }
                }
        });
    });
}

} // namespace penumbra
