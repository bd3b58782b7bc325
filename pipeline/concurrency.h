// Running independent pieces of work side by side on the current task arena (TBB).
#pragma once

#include <cstddef>
#include <functional>

namespace specbake {

// Runs work(0) ... work(count - 1) on the current task arena's threads, several items at a time. Each item
// runs isolated: its own parallel loops still use every thread, but a thread waiting inside one item never
// starts another, so at most one item per thread is in flight (memory stays bounded). Items must not
// depend on their order; callers collect results by index, so outputs do not depend on the thread count.
void for_each_concurrently(size_t count, const std::function<void(size_t)>& work);

}  // namespace specbake
