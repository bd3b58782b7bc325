// The batch runner: every input runs once whatever --jobs is, one error line per failed input, exit codes.
#include "cli/batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>

using namespace specbake;

namespace {

size_t count_of(const std::string& text, const std::string& needle) {
    size_t n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    return n;
}

}  // namespace

TEST(Batch, MixedOutcomesGiveExitOneAndOneErrorLineEach) {
    const std::vector<std::string> inputs{"a.gltf", "b.gltf", "c.gltf", "d.gltf", "e.gltf"};
    for (int jobs : {1, 2, 0}) {
        std::vector<std::atomic<int>> runs(inputs.size());
        RunSettings settings;
        settings.jobs = jobs;
        testing::internal::CaptureStderr();
        const BatchSummary s = run_batch(
            inputs,
            [&](size_t i) -> ItemOutcome {
                ++runs[i];
                if (i == 1) return {ItemStatus::failed, "b.gltf: not a glTF file"};
                if (i == 3) throw std::runtime_error("boom");
                if (i == 4) return {ItemStatus::up_to_date, ""};
                return {ItemStatus::done, ""};
            },
            settings);
        const std::string err = testing::internal::GetCapturedStderr();
        for (auto& r : runs) EXPECT_EQ(r.load(), 1);
        EXPECT_EQ(s.done, 2);
        EXPECT_EQ(s.up_to_date, 1);
        EXPECT_EQ(s.failed, 2);
        EXPECT_EQ(s.exit_code(), 1);
        EXPECT_EQ(count_of(err, "specbake: error:"), 2u) << err;
        EXPECT_NE(err.find("specbake: error: b.gltf: not a glTF file\n"), std::string::npos) << err;
        EXPECT_NE(err.find("specbake: error: d.gltf: internal error: boom\n"), std::string::npos) << err;
        EXPECT_NE(err.find("2 done, 1 up to date, 2 failed"), std::string::npos) << err;
        EXPECT_EQ(count_of(err, "] "), inputs.size()) << "one progress line per input:\n" << err;
    }
}

TEST(Batch, QuietPrintsOnlyErrorsAndSuccessExitsZero) {
    const std::vector<std::string> inputs{"a", "b"};
    RunSettings settings;
    settings.verbosity = Verbosity::quiet;
    testing::internal::CaptureStderr();
    const BatchSummary s = run_batch(inputs, [](size_t) { return ItemOutcome{}; }, settings);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    EXPECT_EQ(s.done, 2);
    EXPECT_EQ(s.exit_code(), 0);
}
