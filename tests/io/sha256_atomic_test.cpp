#include "io/atomic_file.h"
#include "io/manifest.h"
#include "io/sha256.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
