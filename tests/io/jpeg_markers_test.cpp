// The JPEG marker check (io/image/jpeg_markers.cpp) on JPEGs built here: the metadata segments OpenImageIO would
// read past the end of are refused with one line naming the file, wherever libjpeg's marker walk finds
// them; JPEGs written by libjpeg (through OpenImageIO) with Exif, XMP, ICC, IPTC and comment segments load
// with the pixels OpenImageIO itself reads.
#include "io/image/image_io.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace specbake::io {
namespace {
namespace fs = std::filesystem;

using Bytes = std::string;

Bytes segment(uint8_t marker, const Bytes& data) {
    const size_t n = data.size() + 2;
    return Bytes{char(0xFF), char(marker), char(n >> 8), char(n & 0xFF)} + data;
}

// A 16x16 RGB JPEG with a gradient, from OpenImageIO's writer (libjpeg); `progressive` makes it a
// multi-scan file. `with_metadata` adds a comment (COM), Exif and IPTC fields (APP1, APP13) and an ICC
// profile (APP2), which the writer puts into segments of their own.
Bytes write_jpeg(const fs::path& dir, bool progressive, bool with_metadata) {
    fs::create_directories(dir);
    const fs::path p = dir / (std::string(progressive ? "progressive" : "baseline") + (with_metadata ? "_meta" : "") + ".jpg");
    OIIO::ImageSpec spec(16, 16, 3, OIIO::TypeDesc::UINT8);
    if (progressive) spec.attribute("jpeg:progressive", 1);
    if (with_metadata) {
        spec.attribute("ImageDescription", "a comment");
        spec.attribute("Exif:FNumber", 2.8f);
        spec.attribute("Keywords", "roughness; normal");
        // An ICC header (ICC.1:2010 Sec. 7.2: size, 'acsp' signature) and no tags: a profile's structure.
        std::vector<uint8_t> icc(132, 0);
        icc[3] = 132;
        icc[36] = 'a', icc[37] = 'c', icc[38] = 's', icc[39] = 'p';
        spec.attribute("ICCProfile", OIIO::TypeDesc(OIIO::TypeDesc::UINT8, int(icc.size())), icc.data());
    }
    std::vector<uint8_t> px(16 * 16 * 3);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) px[(y * 16 + x) * 3 + c] = uint8_t(16 * x + 8 * c + y);
    auto out = OIIO::ImageOutput::create(p.string());
    EXPECT_TRUE(out);
    EXPECT_TRUE(out->open(p.string(), spec));
    EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, px.data()));
    out->close();
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), {}};
}

// The segments of a JPEG up to its first SOS: (marker, data) in file order. For the tests' own files only,
// which have no stray bytes.
std::vector<std::pair<uint8_t, Bytes>> header_segments(const Bytes& j) {
    std::vector<std::pair<uint8_t, Bytes>> out;
    for (size_t at = 2; at + 4 <= j.size() && uint8_t(j[at]) == 0xFF;) {
        const uint8_t marker = uint8_t(j[at + 1]);
        const size_t n = size_t(uint8_t(j[at + 2])) << 8 | uint8_t(j[at + 3]);
        out.emplace_back(marker, j.substr(at + 4, n - 2));
        if (marker == 0xDA) break;
        at += 2 + n;
    }
    return out;
}

// Where the first scan's entropy-coded data ends: the first marker after the first SOS.
size_t first_scan_end(const Bytes& j) {
    size_t at = 2;
    while (uint8_t(j[at + 1]) != 0xDA) at += 2 + (size_t(uint8_t(j[at + 2])) << 8 | uint8_t(j[at + 3]));
    at += 2 + (size_t(uint8_t(j[at + 2])) << 8 | uint8_t(j[at + 3]));
    while (!(uint8_t(j[at]) == 0xFF && uint8_t(j[at + 1]) != 0 && (uint8_t(j[at + 1]) & 0xF8) != 0xD0)) ++at;
    return at;
}

Result<DecodedImage> decode(const Bytes& j, const std::string& name) {
    return decode_image_memory({reinterpret_cast<const uint8_t*>(j.data()), j.size()}, name);
}

void expect_refused(const Bytes& j, const std::string& name, const std::string& what) {
    auto r = decode(j, name);
    ASSERT_FALSE(r) << name << " was decoded";
    const std::string& m = r.error().message;
    EXPECT_EQ(m.rfind(name + ": corrupt JPEG (", 0), 0u) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
}

// The pixels OpenImageIO reads from the same bytes, as the independent reference.
void expect_loads_as_openimageio_reads(const Bytes& j, const fs::path& dir, const std::string& name) {
    const fs::path p = dir / name;
    std::ofstream(p, std::ios::binary) << j;
    auto in = OIIO::ImageInput::open(p.string());
    ASSERT_TRUE(in) << name << ": " << OIIO::geterror();
    std::vector<float> expected(size_t(in->spec().width) * in->spec().height * in->spec().nchannels);
    ASSERT_TRUE(in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, expected.data()));
    for (auto decoded : {decode(j, name), decode_image(p)}) {
        ASSERT_TRUE(decoded) << decoded.error().message;
        EXPECT_EQ(decoded->info.format, "jpeg");
        ASSERT_EQ(decoded->image.pixels.size(), expected.size()) << name;
        for (size_t i = 0; i < expected.size(); ++i) ASSERT_NEAR(decoded->image.pixels[i], expected[i], 1e-6f) << name << " value " << i;
    }
}

const Bytes unterminated_app1 = segment(0xE1, "\x04\x04\x04\x04");

TEST(JpegMarkers, SegmentsBehindAStuffedZeroAreChecked) {
    // The two long-run fuzz reproducers (fuzz/regressions/image/jpeg-oiio-strcmp-overread-*.jpg): libjpeg
    // discards an FF 00 pair between segments and reads on, reaching an APPn whose identifier has no NUL,
    // which OpenImageIO strcmp()s past the end of the heap block. Read as a segment, FF 00 01 00 would
    // claim 256 bytes and hide the APP1; the old check did that and passed the file through.
    const Bytes j = write_jpeg(fs::temp_directory_path() / ("specbake_jpeg_ff00_" + std::to_string(::getpid())), false, false);
    const Bytes soi = j.substr(0, 2), rest = j.substr(2);
    expect_refused(soi + "\xFF" + Bytes(1, '\0') + unterminated_app1 + rest, "ff00.jpg", "APP1 segment at byte 4 without a terminated identifier");
    expect_refused(soi + "\xFF" + Bytes(1, '\0') + "\x01" + Bytes(1, '\0') + unterminated_app1 + rest, "ff00-hidden.jpg",
                   "APP1 segment at byte 6");
    // The same behind the tables, as in the reproducers (after the DQT segments, before SOF).
    const auto segs = header_segments(j);
    size_t after_dqt = 2;
    for (const auto& [marker, data] : segs) {
        after_dqt += 4 + data.size();
        if (marker == 0xDB) break;
    }
    expect_refused(j.substr(0, after_dqt) + "\xFF" + Bytes(1, '\0') + unterminated_app1 + j.substr(after_dqt), "after-dqt.jpg",
                   "without a terminated identifier");
    // APP2 and APP13, whose identifiers OpenImageIO strcmp()s as well.
    expect_refused(soi + "\xFF" + Bytes(1, '\0') + segment(0xE2, "ICC_PROFILE") + rest, "icc.jpg", "APP2 segment");
    expect_refused(soi + "\xFF" + Bytes(1, '\0') + segment(0xED, "Photoshop 3.0") + rest, "iptc.jpg", "APP13 segment");
    // An empty APP1 (length 2): libjpeg saves zero bytes, which strcmp reads past.
    expect_refused(soi + segment(0xE1, "") + rest, "empty.jpg", "APP1 segment at byte 2");
}

TEST(JpegMarkers, ABogusSegmentLengthDoesNotHideWhatFollows) {
    // libjpeg ignores an APPn length below 2 and reads on right after it (save_marker), so the APP1 behind
    // it is saved and compared.
    const Bytes j = write_jpeg(fs::temp_directory_path() / ("specbake_jpeg_len_" + std::to_string(::getpid())), false, false);
    for (const Bytes length : {Bytes(2, '\0'), Bytes("\0\1", 2)})
        expect_refused(j.substr(0, 2) + "\xFF\xE1" + length + unterminated_app1 + j.substr(2), "bogus-length.jpg", "APP1 segment at byte 6");
}

TEST(JpegMarkers, SegmentsBetweenTheScansOfAProgressiveJpegAreChecked) {
    // jpeg_start_decompress reads a multi-scan file to its end before OpenImageIO looks at the saved
    // segments, so an APPn after the first scan is compared too; and a file cut inside one is padded by
    // libjpeg with fake EOI markers, which hold no NUL.
    const fs::path dir = fs::temp_directory_path() / ("specbake_jpeg_prog_" + std::to_string(::getpid()));
    const Bytes prog = write_jpeg(dir, true, false);
    const size_t e = first_scan_end(prog);
    expect_refused(prog.substr(0, e) + unterminated_app1 + prog.substr(e), "between-scans.jpg", "without a terminated identifier");
    expect_refused(prog.substr(0, e) + "\xFF\xE1\x01" + Bytes(1, '\0') + "Exif", "cut.jpg", "cut by the end of the file");
    expect_refused(prog.substr(0, e) + "\xFF\xE1", "cut-at-length.jpg", "cut by the end of the file");
    // A baseline (single-scan) file is decoded without reading past its scan: segments there are never
    // compared, so the file loads.
    const Bytes base = write_jpeg(dir, false, false);
    const size_t b = first_scan_end(base);
    expect_loads_as_openimageio_reads(base.substr(0, b) + unterminated_app1 + base.substr(b), dir, "after-single-scan.jpg");
    fs::remove_all(dir);
}

TEST(JpegMarkers, JpegsWithEveryKindOfMetadataLoad) {
    const fs::path dir = fs::temp_directory_path() / ("specbake_jpeg_meta_" + std::to_string(::getpid()));
    const Bytes xmp = segment(0xE1, Bytes("http://ns.adobe.com/xap/1.0/", 29) +
                                        "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\"><rdf:RDF xmlns:rdf=\"http://www.w3.org/1999/"
                                        "02/22-rdf-syntax-ns#\"/></x:xmpmeta>");
    for (bool progressive : {false, true}) {
        const Bytes j = write_jpeg(dir, progressive, true);
        // The writer produced the segments this test is about.
        bool exif = false, icc = false, iptc = false, com = false;
        for (const auto& [marker, data] : header_segments(j)) {
            exif |= marker == 0xE1 && data.compare(0, 6, Bytes("Exif\0\0", 6)) == 0;
            icc |= marker == 0xE2 && data.compare(0, 12, Bytes("ICC_PROFILE\0", 12)) == 0;
            iptc |= marker == 0xED && data.compare(0, 14, Bytes("Photoshop 3.0\0", 14)) == 0;
            com |= marker == 0xFE;
        }
        EXPECT_TRUE(exif && icc && iptc && com) << exif << icc << iptc << com;
        const std::string name = progressive ? "progressive" : "baseline";
        expect_loads_as_openimageio_reads(j, dir, name + ".jpg");
        // An XMP packet (OpenImageIO's writer leaves it out) and fill bytes before the next marker.
        expect_loads_as_openimageio_reads(j.substr(0, 2) + xmp + "\xFF\xFF" + j.substr(2), dir, name + "-xmp.jpg");
    }
    // A real texture (the shared assets' JPEG normal map), when present.
    const fs::path asset = fs::path(SPECBAKE_ASSETS_DIR) / "normalmaps" / "GlassVaseFlowers_sorrel_jpeg" / "shrub_sorrel_01_normal_1k.jpg";
    if (fs::exists(asset)) {
        std::ifstream f(asset, std::ios::binary);
        expect_loads_as_openimageio_reads({std::istreambuf_iterator<char>(f), {}}, dir, "asset.jpg");
    } else {
        std::printf("asset JPEG %s absent: the real-texture case is skipped\n", asset.string().c_str());
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace specbake::io
