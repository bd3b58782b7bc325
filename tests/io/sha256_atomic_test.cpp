#include "io/files/atomic_write.h"
#include "io/files/file_read.h"
#include "io/files/input_policy.h"
#include "io/output/manifest.h"
#include "io/files/sha256.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <mutex>
#include <span>
#include <vector>

namespace fs = std::filesystem;
using namespace specbake::io;

// FIPS 180-4 example vectors.
TEST(Sha256, KnownVectors) {
    EXPECT_EQ(sha256_hex({}), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    const std::string abc = "abc";
    Sha256 s;
    s.update(abc);
    EXPECT_EQ(s.hex(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    Sha256 two_blocks;
    two_blocks.update(std::string("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"));
    EXPECT_EQ(two_blocks.hex(), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, ChunkingDoesNotMatter) {
    std::string million(1000000, 'a');
    Sha256 whole;
    whole.update(million);
    Sha256 pieces;
    for (size_t i = 0; i < million.size(); i += 997) pieces.update(million.substr(i, 997));
    const std::string expected = "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0";
    EXPECT_EQ(whole.hex(), expected);
    EXPECT_EQ(pieces.hex(), expected);
}

// The CPU-extension path (when this machine has one) and the portable path agree on every length around
// the block and padding boundaries, and with the FIPS 180-4 vectors.
TEST(Sha256, PortableAndCpuPathsAgree) {
    EXPECT_EQ(sha256_hex_portable({}), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    const std::string two_blocks = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
    EXPECT_EQ(sha256_hex_portable(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(two_blocks.data()),
                                                           two_blocks.size())),
              "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    std::vector<uint8_t> data(4099);
    uint32_t x = 12345;
    for (uint8_t& b : data) b = uint8_t((x = x * 1664525u + 1013904223u) >> 24);
    for (size_t n : {0, 1, 55, 56, 63, 64, 65, 119, 120, 127, 128, 129, 1000, 4099}) {
        const std::span<const uint8_t> part(data.data(), n);
        EXPECT_EQ(sha256_hex(part), sha256_hex_portable(part)) << n << " bytes";
    }
    if (!sha256_uses_cpu_extensions()) GTEST_SKIP() << "this CPU has no SHA extensions; only the portable path ran";
}

// Ranges hashed together, several interleaved per core, against the portable path one by one: lengths
// around the block and padding boundaries, empty ranges, and ranges longer than a 4 MiB window, so the
// lanes start, finish and are refilled at different points; FIPS 180-4's million 'a's as a fixed vector.
// Every byte is inside exactly one window, and each window is announced before it is hashed.
TEST(Sha256, RangesHashedInLanesMatchOneByOne) {
    std::vector<uint8_t> data((size_t(9) << 20) + 777);
    uint32_t x = 987654321;
    for (uint8_t& b : data) b = uint8_t((x = x * 1664525u + 1013904223u) >> 24);
    const std::string million(1000000, 'a');
    std::vector<std::span<const uint8_t>> ranges;
    for (size_t n : {size_t(0), size_t(1), size_t(55), size_t(64), size_t(65), size_t(129), size_t(4099),
                     (size_t(4) << 20) + 1, data.size(), size_t(3) << 20, size_t(0), size_t(200000)})
        ranges.push_back(std::span<const uint8_t>(data.data() + (data.size() - n) / 3, n));
    ranges.push_back(std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(million.data()), million.size()));
    std::mutex m;
    std::vector<std::vector<std::pair<size_t, size_t>>> announced(ranges.size()), done(ranges.size());
    const std::vector<std::string> digests = sha256_ranges(
        ranges,
        [&](size_t r, size_t offset, size_t size) {
            std::lock_guard lock(m);
            announced[r].emplace_back(offset, size);
        },
        [&](size_t r, size_t offset, size_t size) {
            std::lock_guard lock(m);
            ASSERT_FALSE(announced[r].empty());
            EXPECT_EQ(announced[r].back(), std::make_pair(offset, size)) << "window of range " << r << " hashed unannounced";
            done[r].emplace_back(offset, size);
        });
    ASSERT_EQ(digests.size(), ranges.size());
    for (size_t r = 0; r < ranges.size(); ++r) {
        EXPECT_EQ(digests[r], sha256_hex_portable(ranges[r])) << "range " << r << ", " << ranges[r].size() << " bytes";
        size_t covered = 0;
        for (const auto& [offset, size] : done[r]) {
            EXPECT_EQ(offset, covered) << "range " << r;
            EXPECT_LE(size, size_t(4) << 20);
            covered += size;
        }
        EXPECT_EQ(covered, ranges[r].size()) << "range " << r;
    }
    EXPECT_EQ(digests.back(), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
    EXPECT_TRUE(sha256_ranges({}).empty());
}

TEST(Sha256, FilesHashedTogetherMatchOneByOne) {
    const fs::path dir = fs::temp_directory_path() / "specbake_sha_files_test";
    fs::remove_all(dir);
    std::vector<fs::path> files;
    for (int i = 0; i < 5; ++i) {
        files.push_back(dir / ("f" + std::to_string(i) + ".bin"));
        ASSERT_TRUE(write_file_atomic(files.back(), std::string(size_t(i) * 70001 + 3, char('a' + i))).ok());
    }
    auto all = sha256_files(files);
    ASSERT_TRUE(all.ok());
    ASSERT_EQ(all->size(), files.size());
    for (size_t i = 0; i < files.size(); ++i) {
        const std::string content(i * 70001 + 3, char('a' + i));
        EXPECT_EQ((*all)[i], sha256_hex_portable(std::span<const uint8_t>(
                                 reinterpret_cast<const uint8_t*>(content.data()), content.size())));
    }
    files.push_back(dir / "missing.bin");
    auto missing = sha256_files(files);
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find("missing.bin"), std::string::npos);
    fs::remove_all(dir);
}

TEST(AtomicFile, WritesAndLeavesNoTemporary) {
    const fs::path dir = fs::temp_directory_path() / "specbake_atomic_test";
    fs::remove_all(dir);
    ASSERT_TRUE(write_file_atomic(dir / "sub" / "a.txt", std::string("hello")).ok());
    auto bytes = read_file(dir / "sub" / "a.txt");
    ASSERT_TRUE(bytes.ok());
    EXPECT_EQ(std::string(bytes->begin(), bytes->end()), "hello");
    int files = 0;
    for (auto& e : fs::directory_iterator(dir / "sub")) files += e.is_regular_file();
    EXPECT_EQ(files, 1);
    {
        AtomicOutput abandoned(dir / "sub" / "b.bin");
        std::ofstream(abandoned.temp_path()) << "partial";
    }
    EXPECT_FALSE(fs::exists(dir / "sub" / "b.bin"));
    files = 0;
    for (auto& e : fs::directory_iterator(dir / "sub")) files += e.is_regular_file();
    EXPECT_EQ(files, 1);
    fs::remove_all(dir);
}

TEST(AtomicFile, ReadErrorsNameTheFile) {
    auto missing = read_file("/nonexistent/specbake/x.png");
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find("/nonexistent/specbake/x.png"), std::string::npos);
}

TEST(AtomicFile, OutputFolderHoldingAnInputIsRejected) {
    const fs::path dir = fs::temp_directory_path() / "specbake_inout_test";
    fs::create_directories(dir);
    std::ofstream(dir / "in.png") << "x";
    const fs::path inputs[] = {dir / "in.png"};
    EXPECT_FALSE(check_output_not_input(dir, inputs).ok());
    EXPECT_TRUE(check_output_not_input(dir / "out", inputs).ok());
    fs::remove_all(dir);
}

TEST(Manifest, RoundTripAndHashes) {
    const fs::path dir = fs::temp_directory_path() / "specbake_manifest_test";
    fs::remove_all(dir);
    ASSERT_TRUE(write_file_atomic(dir / "r.bin", std::string("abc")).ok());
    Manifest m;
    m.version = "1.2.3";
    m.settings = {{"filter", "projected"}};
    m.outputs.push_back({"roughness", "r.bin", "ktx2", 4, 2, 3, 1, "", {{"vkFormat", 9}}});
    ASSERT_TRUE(write_manifest(dir, m).ok());
    auto back = read_manifest(dir / "manifest.json");
    ASSERT_TRUE(back.ok()) << back.error().message;
    ASSERT_EQ(back->outputs.size(), 1u);
    EXPECT_EQ(back->outputs[0].sha256, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    EXPECT_EQ(back->outputs[0].mips, 3);
    EXPECT_EQ(back->outputs[0].extra["vkFormat"], 9);
    EXPECT_EQ(back->settings["filter"], "projected");
    fs::remove_all(dir);
}
