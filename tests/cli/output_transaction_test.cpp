// Transactional output folders end to end (docs/build-pipelines.md#output-folders-are-transactional): the
// real executable is killed at random moments, interrupted by SIGINT/SIGTERM/SIGHUP, starved of disk space,
// made to throw, run twice into one folder, pointed at a read-only folder and at an unwritable depfile;
// afterwards the folder must hold exactly the previous complete bake or the new complete one, and no
// temporaries.
#include "io/output/output_folder.h"
#include "pipeline/scene_job.h"
#include "pipeline/texture_job.h"

#include "scene_test_util.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using scene_test::slurp;

namespace {

using Tree = std::map<std::string, std::string>;

// Regular files under `root` -> content; with `all` false, the lock file, stages and temporaries of
// interrupted runs are left out (they are checked separately).
Tree tree(const fs::path& root, bool all = true) {
    Tree out;
    if (!fs::exists(root)) return out;
    for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
        const std::string rel = fs::relative(it->path(), root).generic_string();
        const std::string name = it->path().filename().string();
        const bool ours = name == ".specbake.lock" || name.rfind(".specbake-stage-", 0) == 0 ||
                          name.find(".tmp") != std::string::npos;
        if (ours && !all) {
            it.disable_recursion_pending();
            continue;
        }
        if (it->is_regular_file()) out[rel] = slurp(it->path());
    }
    return out;
}

// Every hidden entry (a leftover, lock or stage) under `root`.
std::vector<std::string> hidden_entries(const fs::path& root) {
    std::vector<std::string> out;
    if (!fs::exists(root)) return out;
    for (const auto& e : fs::recursive_directory_iterator(root))
        if (e.path().filename().string()[0] == '.') out.push_back(fs::relative(e.path(), root).generic_string());
    return out;
}

// The manifest lists exactly the folder's files: outputs, manifest.json, and a demo bake's inputs.
void expect_manifest_lists_folder(const fs::path& dir) {
    const nlohmann::json m = nlohmann::json::parse(slurp(dir / "manifest.json"));
    std::set<std::string> listed{"manifest.json"};
    for (const auto& o : m["outputs"]) listed.insert(o["path"].get<std::string>());
    if (m["settings"].value("demo", false))
        for (const auto& in : m["inputs"]) listed.insert(in["path"].get<std::string>());
    std::set<std::string> present;
    for (const auto& [rel, content] : tree(dir)) present.insert(rel);
    EXPECT_EQ(listed, present) << dir;
}

// A tangent-space normal map of smooth bumps and noise, written by OpenImageIO (8-bit PNG).
void write_normal_map(const fs::path& path, int size, uint32_t seed) {
    std::vector<uint8_t> px(size_t(size) * size * 3);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> noise(-0.15, 0.15);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double gx = 0.8 * std::sin(x * 0.19) * std::cos(y * 0.07) + noise(rng);
            const double gy = 0.8 * std::cos(x * 0.05) * std::sin(y * 0.23) + noise(rng);
            const double len = std::sqrt(gx * gx + gy * gy + 1.0);
            uint8_t* t = px.data() + (size_t(y) * size + x) * 3;
            t[0] = uint8_t(std::lround((0.5 - 0.5 * gx / len) * 255));
            t[1] = uint8_t(std::lround((0.5 - 0.5 * gy / len) * 255));
            t[2] = uint8_t(std::lround((0.5 + 0.5 / len) * 255));
        }
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path.string(), OIIO::ImageSpec(size, size, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    ASSERT_TRUE(out->close());
}

struct Child {
    pid_t pid = -1;
    fs::path out, err;
};

// Starts `specbake <args>` with stdout/stderr in files; `file_size_limit` > 0 sets RLIMIT_FSIZE (writes past
// it fail with EFBIG, as on a full disk; SIGXFSZ is ignored so the write reports the error).
Child spawn(const std::vector<std::string>& args, const fs::path& logs, const std::string& tag,
            rlim_t file_size_limit = 0) {
    Child c;
    c.out = logs / (tag + ".out");
    c.err = logs / (tag + ".err");
    std::vector<std::string> argv_s{SPECBAKE_EXE};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    c.pid = ::fork();
    if (c.pid == 0) {
        const int o = ::open(c.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        const int e = ::open(c.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        ::dup2(o, 1);
        ::dup2(e, 2);
        if (file_size_limit) {
            std::signal(SIGXFSZ, SIG_IGN);
            const rlimit lim{file_size_limit, file_size_limit};
            ::setrlimit(RLIMIT_FSIZE, &lim);
        }
        std::vector<char*> argv;
        for (std::string& a : argv_s) argv.push_back(a.data());
        argv.push_back(nullptr);
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    return c;
}

int wait_status(const Child& c) {
    int status = 0;
    while (::waitpid(c.pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
}

struct Finished {
    int exit_code = -1;
    int signal = 0;
    std::string out, err;
};

Finished run(const std::vector<std::string>& args, const fs::path& logs, rlim_t file_size_limit = 0) {
    const Child c = spawn(args, logs, "run", file_size_limit);
    const int status = wait_status(c);
    Finished f;
    f.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    f.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    f.out = slurp(c.out);
    f.err = slurp(c.err);
    return f;
}

class OutputTransactionCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = scene_test::temp_dir(std::string("tx_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_ / "in");
        fs::create_directories(dir_ / "logs");
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path in(const std::string& name) const { return dir_ / "in" / name; }
    fs::path logs() const { return dir_ / "logs"; }

    // Bakes `args` into a folder of its own and returns its files: the complete bake those arguments give.
    Tree reference(std::vector<std::string> args, const std::string& name) {
        args.insert(args.end(), {"-o", (dir_ / name).string()});
        const Finished f = run(args, logs());
        EXPECT_EQ(f.exit_code, 0) << f.err;
        return tree(dir_ / name);
    }

    // Copies a reference bake into `out`, replacing what is there.
    void restore(const std::string& name, const fs::path& out) {
        fs::remove_all(out);
        fs::copy(dir_ / name, out, fs::copy_options::recursive);
    }

    fs::path dir_;
};

// The folder, once `inspect --check` (or the next run) has rolled an interrupted commit forward, is the old
// or the new bake, and the only problems reported are leftovers of the interrupted run.
TEST_F(OutputTransactionCli, KillAtRandomMomentsLeavesThePreviousOrTheNewBake) {
    write_normal_map(in("n.png"), 768, 1);
    const std::vector<std::string> old_args{"-q", "texture", "--normal", in("n.png").string()};
    const std::vector<std::string> new_args{"-q", "texture", "--normal", in("n.png").string(), "--format", "dds",
                                            "--isotropic", "max", "--force"};
    const Tree old_bake = reference(old_args, "old");
    const Tree new_bake = reference(new_args, "new");
    ASSERT_NE(old_bake, new_bake);
    const fs::path out = dir_ / "out";
    std::vector<std::string> args = new_args;
    args.insert(args.end(), {"-o", out.string()});

    // The duration of an uninterrupted rebake sets the range of the kill times.
    restore("old", out);
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(run(args, logs()).exit_code, 0);
    const double full_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

    std::mt19937 rng(7);
    int saw_old = 0, saw_new = 0, with_leftovers = 0, rolled_forward = 0;
    constexpr int kRuns = 40;
    for (int i = 0; i < kRuns; ++i) {
        // Half the kills anywhere in the run, half in its last fifth, where the commit happens.
        std::uniform_real_distribution<double> when(i % 2 ? 0.8 * full_ms : 0.0, 1.1 * full_ms);
        const double delay_ms = when(rng);
        SCOPED_TRACE("kill -9 after " + std::to_string(delay_ms) + " ms of ~" + std::to_string(full_ms));
        restore("old", out);
        const Child c = spawn(args, logs(), "kill");
        std::this_thread::sleep_for(std::chrono::microseconds(int64_t(delay_ms * 1000)));
        ::kill(c.pid, SIGKILL);
        wait_status(c);

        const Finished check = run({"inspect", "--check", out.string()}, logs());
        std::istringstream lines(check.err);
        for (std::string line; std::getline(lines, line);) {
            if (line.rfind("specbake: note:", 0) == 0) continue;
            EXPECT_NE(line.find("left by an interrupted run"), std::string::npos) << line;
        }
        with_leftovers += check.exit_code != 0;
        rolled_forward += check.err.find("finished the commit") != std::string::npos;
        const Tree now = tree(out, false);
        const bool is_old = now == old_bake, is_new = now == new_bake;
        EXPECT_TRUE(is_old || is_new) << "the folder mixes the two bakes";
        saw_old += is_old;
        saw_new += is_new;

        // The next run removes the leftovers and completes.
        ASSERT_EQ(run(args, logs()).exit_code, 0);
        EXPECT_EQ(tree(out), new_bake);
    }
    std::printf("[          ] %d kills: %d left the previous bake, %d the new one (%d of them by finishing an "
                "interrupted commit), %d with leftovers\n",
                kRuns, saw_old, saw_new, rolled_forward, with_leftovers);
}

TEST_F(OutputTransactionCli, InterruptSignalsRemoveEveryTemporary) {
    write_normal_map(in("n.png"), 2048, 2);
    const Tree old_bake = reference({"-q", "texture", "--normal", in("n.png").string()}, "old");
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        SCOPED_TRACE(strsignal(sig));
        const fs::path out = dir_ / "out";
        restore("old", out);
        // A temporary of a run of an earlier version, killed long ago: found by inspect, removed by the next run.
        std::ofstream(out / ".texture_kernel.tmp999999-0.ktx2") << "stale";
        const Finished check = run({"inspect", "--check", out.string()}, logs());
        EXPECT_EQ(check.exit_code, 1);
        EXPECT_NE(check.err.find(".texture_kernel.tmp999999-0.ktx2: left by an interrupted run"), std::string::npos)
            << check.err;

        const Child c = spawn({"texture", "--normal", in("n.png").string(), "--format", "exr", "--force", "-o",
                               out.string()},
                              logs(), "signal");
        // Interrupted while it writes: once its stage holds a file.
        const fs::path stage = out / (".specbake-stage-" + std::to_string(c.pid));
        for (int wait = 0; wait < 2000; ++wait) {
            std::error_code ec;
            if (fs::exists(stage, ec) && !fs::is_empty(stage, ec)) break;
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        ::kill(c.pid, sig);
        const int status = wait_status(c);
        EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << slurp(c.err);
        EXPECT_EQ(hidden_entries(out), std::vector<std::string>{}) << "an interrupted run left files behind";
        EXPECT_EQ(tree(out), old_bake);
    }
}

// A full disk: the new bake does not fit, the old one stays, with nothing else, and the error names the
// file and the system's reason.
TEST_F(OutputTransactionCli, FullDiskLeavesThePreviousBake) {
    write_normal_map(in("n.png"), 512, 3);
    const Tree old_bake = reference({"-q", "texture", "--normal", in("n.png").string()}, "old");
    const fs::path out = dir_ / "out";
    // Files may not grow past 200 KB (the lean texture needs 700 KB): EFBIG, as ENOSPC would be.
    restore("old", out);
    const Finished limited = run({"texture", "--normal", in("n.png").string(), "--format", "dds", "--force", "-o",
                                  out.string()},
                                 logs(), 200 * 1024);
    EXPECT_EQ(limited.exit_code, 1);
    EXPECT_NE(limited.err.find(std::strerror(EFBIG)), std::string::npos) << limited.err;
    EXPECT_NE(limited.err.find((out / "texture_").string()), std::string::npos) << limited.err;
    EXPECT_EQ(limited.err.find(".tmp"), std::string::npos) << limited.err;
    EXPECT_EQ(limited.err.find(".specbake-stage"), std::string::npos) << limited.err;
    EXPECT_EQ(tree(out), old_bake);

    // A real full file system: a tmpfs just larger than the old bake (needs the right to mount).
    const fs::path mnt = dir_ / "tmpfs";
    fs::create_directories(mnt);
    size_t old_bytes = 0;
    for (const auto& [rel, content] : old_bake) old_bytes += content.size();
    const std::string options = "size=" + std::to_string(old_bytes + 256 * 1024);
    if (::mount("tmpfs", mnt.c_str(), "tmpfs", 0, options.c_str()) != 0)
        GTEST_SKIP() << "cannot mount a tmpfs here (" << std::strerror(errno) << "); the file-size limit case ran";
    restore("old", mnt / "out");
    const Finished full = run({"texture", "--normal", in("n.png").string(), "--format", "dds", "--force", "-o",
                               (mnt / "out").string()},
                              logs());
    EXPECT_EQ(full.exit_code, 1);
    EXPECT_NE(full.err.find(std::strerror(ENOSPC)), std::string::npos) << full.err;
    EXPECT_EQ(full.err.find(".tmp"), std::string::npos) << full.err;
    EXPECT_EQ(tree(mnt / "out"), old_bake);
    EXPECT_EQ(hidden_entries(mnt / "out"), std::vector<std::string>{});
    ::umount(mnt.c_str());
}

// An exception in the middle of a bake (here thrown by the progress callback as a file is written): the
// folder keeps its previous bake and no stage.
TEST_F(OutputTransactionCli, ExceptionMidBakeLeavesThePreviousBake) {
    const fs::path out = dir_ / "out";
    specbake::TextureJob job;
    job.demo = true;
    job.output_dir = out;
    ASSERT_TRUE(specbake::run_texture_job(job).ok());
    const Tree before = tree(out);
    job.texture_format.container = specbake::io::TextureContainer::Dds;
    job.progress = [](const std::string& line) {
        if (line.rfind("writing texture_lean", 0) == 0) throw std::runtime_error("injected");
    };
    EXPECT_THROW((void)specbake::run_texture_job(job), std::runtime_error);
    EXPECT_EQ(tree(out), before);

    // The same for a scene, thrown as the scene file is written.
    scene_test::write_test_model(in("sphere.gltf"), true, 1.0, 0.2, 8, 16);
    specbake::SceneJob scene;
    scene.scenes = {in("sphere.gltf")};
    scene.output_dir = dir_ / "scene_out";
    ASSERT_TRUE(specbake::run_scene_job(scene).ok());
    const Tree scene_before = tree(scene.output_dir);
    scene.format = specbake::SceneFormat::Glb;
    scene.progress = [](const std::string& line) {
        if (line.rfind("writing", 0) == 0) throw std::runtime_error("injected");
    };
    EXPECT_THROW((void)specbake::run_scene_job(scene), std::runtime_error);
    EXPECT_EQ(tree(scene.output_dir), scene_before);
}

// While one process holds the folder, a second run waits (and says for whom), then completes.
TEST_F(OutputTransactionCli, SecondRunIntoTheSameFolderWaits) {
    const fs::path out = dir_ / "out";
    auto held = specbake::io::OutputLock::acquire(out, specbake::io::OutputLock::Purpose::write);
    ASSERT_TRUE(held.ok());
    auto lock = std::make_unique<specbake::io::OutputLock>(std::move(*held));
    const Child c = spawn({"texture", "--demo", "-o", out.string()}, logs(), "waiting");
    std::string err;
    for (int wait = 0; wait < 500 && err.find("waiting") == std::string::npos; ++wait) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        err = slurp(c.err);
    }
    EXPECT_NE(err.find("waiting for specbake process " + std::to_string(::getpid())), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(out / "manifest.json"));
    lock.reset();
    const int status = wait_status(c);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(c.err);
    expect_manifest_lists_folder(out);
    EXPECT_EQ(hidden_entries(out), std::vector<std::string>{});

    // Two runs started together: both complete, one after the other, and the folder is one complete bake.
    const Tree demo = tree(out);
    const Child a = spawn({"-q", "texture", "--demo", "--force", "-o", out.string()}, logs(), "a");
    const Child b = spawn({"-q", "texture", "--demo", "--force", "-o", out.string()}, logs(), "b");
    for (const Child* ch : {&a, &b}) {
        const int st = wait_status(*ch);
        EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << slurp(ch->err);
    }
    EXPECT_EQ(tree(out), demo);
}

// A folder holds one bake: a bake of another scene is refused (naming both) and changes nothing; with
// --force it replaces the bake entirely, and the manifest lists exactly the files in the folder.
TEST_F(OutputTransactionCli, BakeOfAnotherSceneIsRefusedUnlessForced) {
    scene_test::write_test_model(in("a.gltf"), true, 1.0, 0.2, 8, 16);
    scene_test::write_test_model(in("b.gltf"), true, 2.0, 0.2, 8, 16);
    const fs::path out = dir_ / "out";
    ASSERT_EQ(run({"-q", "bake", in("a.gltf").string(), "-o", out.string()}, logs()).exit_code, 0);
    const Tree a = tree(out);
    const Finished b = run({"bake", in("b.gltf").string(), "-o", out.string()}, logs());
    EXPECT_EQ(b.exit_code, 1);
    EXPECT_NE(b.err.find("holds the bake of " + in("a.gltf").string()), std::string::npos) << b.err;
    EXPECT_NE(b.err.find("--force"), std::string::npos) << b.err;
    EXPECT_EQ(tree(out), a);

    ASSERT_EQ(run({"-q", "bake", in("b.gltf").string(), "--force", "-o", out.string()}, logs()).exit_code, 0);
    expect_manifest_lists_folder(out);
    EXPECT_FALSE(fs::exists(out / "a.gltf"));
    EXPECT_TRUE(fs::exists(out / "b.gltf"));
    // A rebake of the same scene in another container leaves no file of the first container.
    ASSERT_EQ(run({"-q", "texture", "--demo", "-o", (dir_ / "t").string()}, logs()).exit_code, 0);
    ASSERT_EQ(run({"-q", "texture", "--demo", "--format", "dds", "-o", (dir_ / "t").string()}, logs()).exit_code, 0);
    expect_manifest_lists_folder(dir_ / "t");
    EXPECT_FALSE(fs::exists(dir_ / "t" / "texture_lean.ktx2"));
}

// A read-only output folder: refused before any work, naming the folder and the system's reason, never a
// temporary file.
TEST_F(OutputTransactionCli, ReadOnlyOutputNamesTheFolderAndTheReason) {
    const fs::path ro = dir_ / "ro";
    fs::create_directories(ro);
    std::string reason;
    if (::geteuid() == 0) {
        // Permissions do not stop root: a read-only tmpfs does.
        if (::mount("tmpfs", ro.c_str(), "tmpfs", MS_RDONLY, "size=64k") != 0)
            GTEST_SKIP() << "root, and cannot mount a read-only tmpfs: " << std::strerror(errno);
        reason = std::strerror(EROFS);
    } else {
        fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
        reason = std::strerror(EACCES);
    }
    const Finished f = run({"texture", "--demo", "-o", ro.string()}, logs());
    EXPECT_EQ(f.exit_code, 1);
    EXPECT_NE(f.err.find(ro.string()), std::string::npos) << f.err;
    EXPECT_NE(f.err.find(reason), std::string::npos) << f.err;
    EXPECT_EQ(f.err.find(".tmp"), std::string::npos) << f.err;
    if (::geteuid() == 0) ::umount(ro.c_str());
    else fs::permissions(ro, fs::perms::owner_all);
}

// An unwritable depfile is reported before anything is baked: the output folder is not even created.
TEST_F(OutputTransactionCli, UnwritableDepfileIsReportedBeforeBaking) {
    std::ofstream(dir_ / "a_file") << "x";
    const fs::path out = dir_ / "out";
    const Finished f = run({"texture", "--demo", "-o", out.string(), "--depfile", (dir_ / "a_file" / "x.d").string()},
                           logs());
    EXPECT_EQ(f.exit_code, 1);
    EXPECT_NE(f.err.find("--depfile " + (dir_ / "a_file" / "x.d").string()), std::string::npos) << f.err;
    EXPECT_FALSE(fs::exists(out));
}

// `inspect --check` of a manifest checks every container from its headers and hashes (from mappings
// streamed in windows): each kind of damage is named, and memory stays far below the outputs' size.
TEST_F(OutputTransactionCli, InspectCheckFindsDamageWithoutCopyingFiles) {
    write_normal_map(in("n.png"), 2048, 4);
    auto peak_kb = [&](const fs::path& folder) {
        const Child c = spawn({"inspect", "--check", folder.string()}, logs(), "check");
        int status = 0;
        rusage usage{};
        EXPECT_EQ(::wait4(c.pid, &status, 0, &usage), c.pid);
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << folder << ": " << slurp(c.err);
        return size_t(usage.ru_maxrss);
    };
    for (const char* format : {"ktx2", "dds", "exr", "png"}) {
        const fs::path out = dir_ / format, small = dir_ / (std::string(format) + "_demo");
        ASSERT_EQ(run({"-q", "texture", "--normal", in("n.png").string(), "--format", format, "-o", out.string()},
                      logs())
                      .exit_code,
                  0);
        ASSERT_EQ(run({"-q", "texture", "--demo", "--format", format, "-o", small.string()}, logs()).exit_code, 0);
        size_t largest = 0;
        for (const auto& [rel, content] : tree(out)) largest = std::max(largest, content.size());
        // Reading a whole file into memory would add at least the largest one (45 MB for the KTX2 LEAN
        // texture) to the peak of checking the small demo bake.
        const size_t big_kb = peak_kb(out), small_kb = peak_kb(small);
        EXPECT_LT((big_kb - std::min(big_kb, small_kb)) * 1024, largest / 2)
            << format << ": peak " << big_kb << " KB against " << small_kb << " KB for the demo bake";
    }
    nlohmann::json m = nlohmann::json::parse(slurp(dir_ / "exr" / "manifest.json"));
    m["outputs"][0]["width"] = m["outputs"][0]["width"].get<int>() + 1;
    std::ofstream(dir_ / "exr" / "manifest.json") << m.dump(2);
    const Finished shape = run({"inspect", "--check", (dir_ / "exr").string()}, logs());
    EXPECT_EQ(shape.exit_code, 1);
    EXPECT_NE(shape.err.find("size, channels or mips differ"), std::string::npos) << shape.err;

    // A truncated KTX2 whose manifest hash was updated to match (by sha256sum): the structure check sees it.
    const fs::path lean = dir_ / "ktx2" / "texture_lean.ktx2";
    const std::string bytes = slurp(lean);
    std::ofstream(lean, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() - 4096);
    FILE* p = ::popen(("sha256sum " + scene_test::quote(lean.string())).c_str(), "r");
    ASSERT_TRUE(p);
    char digest[65] = {};
    ASSERT_EQ(std::fread(digest, 1, 64, p), 64u);
    ::pclose(p);
    m = nlohmann::json::parse(slurp(dir_ / "ktx2" / "manifest.json"));
    for (auto& o : m["outputs"])
        if (o["path"] == "texture_lean.ktx2") o["sha256"] = std::string(digest);
    std::ofstream(dir_ / "ktx2" / "manifest.json") << m.dump(2);
    fs::remove(dir_ / "ktx2" / "texture_kernel.ktx2");
    const Finished damaged = run({"inspect", "--check", (dir_ / "ktx2").string()}, logs());
    EXPECT_EQ(damaged.exit_code, 1);
    EXPECT_NE(damaged.err.find("texture_lean.ktx2: KTX2: level 0"), std::string::npos) << damaged.err;
    EXPECT_NE(damaged.err.find("texture_kernel.ktx2: no such file"), std::string::npos) << damaged.err;
}

}  // namespace
