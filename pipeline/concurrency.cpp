#include "pipeline/concurrency.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace specbake {

void for_each_concurrently(size_t count, const std::function<void(size_t)>& work) {
    // One task per item; isolation keeps a thread that waits inside an item's own parallel loops from
    // starting another item, so at most one item per thread is in memory at a time.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) tbb::this_task_arena::isolate([&] { work(i); });
    }, tbb::simple_partitioner());
}

}  // namespace specbake
