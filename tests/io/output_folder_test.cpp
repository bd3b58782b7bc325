// Transactional output folders (io/output/output_folder.h): the lock excludes a second holder, an abandoned stage
// leaves the folder as it was, and a commit stopped after its commit point at any step is rolled forward
// to exactly the new bake by the next lock holder.
#include "io/files/cleanup_registry.h"
#include "io/output/output_folder.h"
#include "tests/io/temp_folder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <sstream>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace specbake::io;

namespace {

fs::path fresh_dir(const std::string& name) {
    return specbake::testing::fresh_test_folder("outfolder", name);
}

void put(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
}

// Every entry under `root` (folders marked with a trailing '/'), relative path -> content.
std::map<std::string, std::string> tree(const fs::path& root) {
    std::map<std::string, std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
        const std::string rel = fs::relative(e.path(), root).generic_string();
        if (e.is_directory()) {
            out[rel + "/"] = "";
        } else {
            std::ifstream in(e.path(), std::ios::binary);
            std::stringstream ss;
            ss << in.rdbuf();
            out[rel] = ss.str();
        }
    }
    return out;
}

// The previous bake: a manifest, two textures, one in a subfolder.
void previous_bake(const fs::path& dir) {
    put(dir / "manifest.json", "old manifest");
    put(dir / "a.ktx2", "old a");
    put(dir / "old_only.ktx2", "old only");
    put(dir / "sub" / "gone.bin", "old sub");
}

const std::map<std::string, std::string> kNew = {
    {"manifest.json", "new manifest"}, {"a.ktx2", "new a"}, {"b.ktx2", "new b"}, {"s2/c.bin", "new c"}, {"s2/", ""}};
const std::vector<std::string> kPreviousFiles = {"a.ktx2", "old_only.ktx2", "sub/gone.bin", "../outside.txt"};

void stage_new(const OutputTransaction& tx) {
    for (const auto& [rel, text] : kNew)
        if (rel.back() != '/') put(tx.stage() / rel, text);
}

}  // namespace

TEST(OutputFolder, CommitReplacesThePreviousBakeAndRemovesItsOtherFiles) {
    const fs::path dir = fresh_dir("commit");
    previous_bake(dir / "out");
    put(dir / "outside.txt", "not ours");
    {
        auto lock = OutputLock::acquire(dir / "out", OutputLock::Purpose::write);
        ASSERT_TRUE(lock.ok()) << lock.error().message;
        auto tx = OutputTransaction::begin(*lock);
        ASSERT_TRUE(tx.ok()) << tx.error().message;
        stage_new(*tx);
        ASSERT_TRUE(tx->commit(kPreviousFiles).ok());
    }
    EXPECT_EQ(tree(dir / "out"), kNew);  // no lock file, no stage, the old-only files and "sub/" gone
    EXPECT_TRUE(fs::exists(dir / "outside.txt"));  // a path leaving the folder is never removed
    fs::remove_all(dir);
}

TEST(OutputFolder, AbandonedStageLeavesThePreviousBake) {
    const fs::path dir = fresh_dir("abandon");
    previous_bake(dir / "out");
    const auto before = tree(dir / "out");
    {
        auto lock = OutputLock::acquire(dir / "out", OutputLock::Purpose::write);
        ASSERT_TRUE(lock.ok());
        auto tx = OutputTransaction::begin(*lock);
        ASSERT_TRUE(tx.ok());
        stage_new(*tx);
    }
    EXPECT_EQ(tree(dir / "out"), before);
    fs::remove_all(dir);
}

// The process dies after the commit record at every step of the roll-forward (the files moved so far in
// the documented order: staged files, removals, manifest, stage): the next holder finishes it.
TEST(OutputFolder, CommitStoppedAtAnyStepIsRolledForward) {
    const fs::path dir = fresh_dir("rollforward");
    std::vector<std::string> staged;
    for (const auto& [rel, text] : kNew)
        if (rel.back() != '/' && rel != "manifest.json") staged.push_back(rel);
    const std::vector<std::string> removals = {"old_only.ktx2", "sub/gone.bin"};
    const size_t steps = staged.size() + removals.size() + 2;
    for (size_t step = 0; step <= steps; ++step) {
        SCOPED_TRACE("stopped after step " + std::to_string(step));
        const fs::path out = dir / ("out" + std::to_string(step));
        previous_bake(out);
        fs::path stage;
        {
            auto lock = OutputLock::acquire(out, OutputLock::Purpose::write);
            ASSERT_TRUE(lock.ok());
            auto tx = OutputTransaction::begin(*lock);
            ASSERT_TRUE(tx.ok());
            stage_new(*tx);
            ASSERT_TRUE(tx->record(kPreviousFiles).ok());
            stage = tx->stage();
        }
        ASSERT_TRUE(fs::exists(stage / kCommitRecordName));
        // What a commit killed after `step` steps left behind.
        size_t done = 0;
        for (const std::string& rel : staged)
            if (done++ < step) {
                fs::create_directories((out / rel).parent_path());
                fs::rename(stage / rel, out / rel);
            }
        for (const std::string& rel : removals)
            if (done++ < step) fs::remove(out / rel);
        if (done++ < step) fs::rename(stage / "manifest.json", out / "manifest.json");
        if (done++ < step) fs::remove_all(stage);
        put(out / kLockFileName, "12345");  // a lock file of the killed process
        {
            auto lock = OutputLock::acquire(out, OutputLock::Purpose::check);
            ASSERT_TRUE(lock.ok()) << lock.error().message;
            EXPECT_EQ(lock->recovery().finished_commit, step <= steps - 1);
        }
        auto expected = kNew;
        if (fs::exists(out / "sub")) expected["sub/"] = "";  // emptied by hand above, not by the roll-forward
        EXPECT_EQ(tree(out), expected);
    }
    fs::remove_all(dir);
}

TEST(OutputFolder, LeftoversOfInterruptedRunsAreFoundAndRemovedByTheNextWriter) {
    const fs::path dir = fresh_dir("leftovers");
    previous_bake(dir / "out");
    const auto before = tree(dir / "out");
    put(dir / "out" / ".specbake-stage-999999" / "x.ktx2", "half");
    put(dir / "out" / ".texture_lean.tmp999999-3.ktx2", "half");
    put(dir / "out" / "scene" / ".scene.tmp999999-0.gltf", "half");
    const FolderLeftovers found = find_leftovers(dir / "out");
    EXPECT_EQ(found.stale.size(), 3u);
    EXPECT_TRUE(found.pending_commits.empty());
    {
        auto check = OutputLock::acquire(dir / "out", OutputLock::Purpose::check);
        ASSERT_TRUE(check.ok());
        EXPECT_EQ(check->recovery().leftovers.size(), 3u);
        EXPECT_FALSE(check->recovery().leftovers_removed);
    }
    EXPECT_EQ(find_leftovers(dir / "out").stale.size(), 3u);  // checking removes nothing
    {
        auto write = OutputLock::acquire(dir / "out", OutputLock::Purpose::write);
        ASSERT_TRUE(write.ok());
        EXPECT_TRUE(write->recovery().leftovers_removed);
    }
    auto expected = before;
    expected["scene/"] = "";
    EXPECT_EQ(tree(dir / "out"), expected);
    fs::remove_all(dir);
}

// A second holder waits until the first releases; the lock file is gone afterwards.
TEST(OutputFolder, SecondLockWaitsForTheFirst) {
    const fs::path dir = fresh_dir("lock");
    auto held = OutputLock::acquire(dir / "out", OutputLock::Purpose::write);
    ASSERT_TRUE(held.ok());
    auto first = std::make_unique<OutputLock>(std::move(*held));
    std::promise<std::string> told;
    auto second = std::async(std::launch::async, [&] {
        auto lock = OutputLock::acquire(dir / "out", OutputLock::Purpose::write,
                                        [&](const std::string& line) { told.set_value(line); });
        return lock.ok();
    });
    const std::string line = told.get_future().get();
    EXPECT_NE(line.find("waiting for specbake process " + std::to_string(::getpid())), std::string::npos) << line;
    EXPECT_EQ(second.wait_for(std::chrono::milliseconds(200)), std::future_status::timeout);
    first.reset();
    EXPECT_TRUE(second.get());
    EXPECT_FALSE(fs::exists(dir / "out" / kLockFileName));
    fs::remove_all(dir);
}

TEST(OutputFolder, RegisteredPathsAreRemovedOnRequest) {
    const fs::path dir = fresh_dir("registry");
    put(dir / "stage" / "a.bin", "x");
    put(dir / "temp.bin", "y");
    register_cleanup(dir / "stage");
    register_cleanup(dir / "temp.bin");
    remove_registered_paths();
    EXPECT_FALSE(fs::exists(dir / "stage"));
    EXPECT_FALSE(fs::exists(dir / "temp.bin"));
    fs::remove_all(dir);
}
