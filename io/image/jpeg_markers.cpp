// The JPEG marker check of the image-decode path (io/image/image_io.h: check_jpeg_markers): the marker walk of
// libjpeg, and the segments OpenImageIO 2.4's JpgInput::open reads past the end of when they are malformed.
#include "io/image/image_io.h"

#include <algorithm>
#include <string>

namespace specbake::io {

// OpenImageIO 2.4 asks libjpeg to save every APPn and COM segment (jpeg_save_markers), then, after
// jpeg_start_decompress, walks the saved list: strcmp(data, "Exif") and strcmp(data,
// "http://ns.adobe.com/xap/1.0/") on each APP1, strcmp(data, "ICC_PROFILE") on each APP2
// (read_icc_profile, which then reads data[12], data[13] and takes data_length - 14), strcmp(data,
// "Photoshop 3.0") on each APP13 (jpeg_decode_iptc, which then reads the 12 header bytes after it and a
// 16-bit size without looking at data_length), and decode_exif(data + 6, data_length - 6). libjpeg's saved
// data is not NUL-terminated, so an identifier without a NUL inside its segment is read past the end of
// the heap block. COM segments are copied with their length and APP0 and APP3-APP12, APP14, APP15 are not
// looked at, so they need nothing.
//
// The segments OpenImageIO sees are the ones libjpeg saves (jdmarker.c), so the walk follows libjpeg:
// - between markers it discards anything up to the next 0xFF, fill bytes 0xFF, and a stuffed zero 0xFF
//   0x00 (next_marker() looks on after it); the two fuzz reproducers hide their unterminated APP1 behind
//   an FF 00 pair inside the bytes this check used to read as one segment;
// - an APPn or COM length below 2 is ignored and the reading goes on right after the length field
//   (save_marker's bogus-length branch), so the segments behind it are saved too;
// - a file cut inside a segment is padded by libjpeg's source manager with fake EOI markers (FF D9 ...):
//   the saved segment then holds no NUL after the real bytes;
// - the headers end at the first SOS, and jpeg_start_decompress reads no further when the frame is
//   sequential and that scan holds every component; otherwise (progressive, or a first scan with fewer
//   components: has_multiple_scans in jdinput.c) it reads the whole file to EOI, saving the APPn segments
//   between the scans as well, so the walk goes on through the entropy-coded data (where an 0xFF is
//   always followed by 0x00 or a restart marker).
// Unknown and unsupported markers make libjpeg fail; the walk reads them by their length and goes on,
// so it never misses a segment libjpeg would save.
Result<void> check_jpeg_markers(std::span<const uint8_t> b, const std::string& name) {
    if (b.size() < 3 || b[0] != 0xFF || b[1] != 0xD8) return {};
    auto corrupt = [&](const std::string& what) -> Result<void> { return make_error(name + ": corrupt JPEG (" + what + ")"); };
    int frame_components = 0;  // from the SOF header; 0 until one is seen
    bool progressive = false;
    for (size_t at = 2; at + 2 <= b.size();) {
        if (b[at] != 0xFF) {  // libjpeg skips stray bytes up to the next marker (with a warning): so does this
            ++at;
            continue;
        }
        const uint8_t marker = b[at + 1];
        if (marker == 0xFF) {  // fill byte
            ++at;
            continue;
        }
        if (marker == 0x00 || marker == 0x01 || marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7)) {
            at += 2;  // stuffed zero, TEM, SOI, RSTn: no length field
            continue;
        }
        if (marker == 0xD9) return {};  // EOI: libjpeg reads nothing after it
        const bool checked = marker == 0xE1 || marker == 0xE2 || marker == 0xED;
        const std::string segment = checked ? "APP" + std::to_string(marker - 0xE0) + " segment at byte " + std::to_string(at) : "";
        if (at + 4 > b.size()) {
            if (checked) return corrupt(segment + " cut by the end of the file");
            return {};  // libjpeg reads a fake EOI and stops
        }
        const size_t length = size_t(b[at + 2]) << 8 | b[at + 3];
        if (length < 2) {
            at += 4;
            continue;
        }
        const size_t stored = std::min(length - 2, b.size() - at - 4);
        const std::span<const uint8_t> data = b.subspan(at + 4, stored);
        if (checked) {
            if (stored < length - 2) return corrupt(segment + " cut by the end of the file");
            const auto nul = std::find(data.begin(), data.end(), uint8_t(0));
            if (nul == data.end()) return corrupt(segment + " without a terminated identifier");
            const std::string id(data.begin(), nul);
            if (marker == 0xE1 && id == "Exif" && data.size() < 6) return corrupt("Exif segment shorter than its header");
            if (marker == 0xE2 && id == "ICC_PROFILE" && data.size() < 14)
                return corrupt("ICC profile segment shorter than its header");
            // "Photoshop 3.0\0", "8BIM", type, 4 padding bytes, then a 2-byte size of what follows.
            if (marker == 0xED && id == "Photoshop 3.0" &&
                (data.size() < 26 || 26 + (size_t(data[24]) << 8 | data[25]) > data.size()))
                return corrupt("Photoshop segment shorter than the sizes it states");
        }
        if (stored < length - 2) return {};  // cut inside another segment: libjpeg reads fake EOIs and stops
        const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
        if (sof && data.size() >= 6) {
            frame_components = data[5];
            progressive = marker == 0xC2 || marker == 0xC6 || marker == 0xCA || marker == 0xCE;
        }
        // SOS: a single scan of every component of a sequential frame is the last thing read before decoding.
        if (marker == 0xDA && frame_components > 0 && !progressive && !data.empty() && data[0] >= frame_components)
            return {};
        at += 2 + length;
    }
    return {};
}

}  // namespace specbake::io
