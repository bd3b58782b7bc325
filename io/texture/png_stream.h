// One PNG file of one mip level, deflated strip by strip as the level's rows are finished, so the level's
// raw bytes need not be held whole (the per-mip PNG outputs of io/texture/texture_writer.h). Grey, grey +
// alpha or RGBA (1, 2 or 4 channels), 8 or 16 bits; linear data (gAMA 1.0, as the OpenImageIO writer marks
// it). The zlib stream is cut into strips of a fixed number of rows, each deflated on its own and ended
// with a sync flush (the last with the stream's end), which is what lets strips be compressed in parallel
// and as they arrive; the bytes depend on the level alone, not on how its rows arrive or on the threads.
#pragma once

#include "core/result.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace specbake::io {

class PngLevelStream {
public:
    // `zlib_level` 1 (fastest) .. 9.
    PngLevelStream(int width, int height, int channels, int bits, int zlib_level);

    // Deflates the strips that rows [0, rows) of the level complete; `texels` is the level's first row,
    // rows tightly packed, 16-bit values in the machine's byte order. Rows below `rows` must stay readable
    // until rows_read() has passed them; `rows` grows from call to call, up to the height. Strips are
    // deflated in parallel (TBB).
    Result<void> add_rows(const uint8_t* texels, int rows);
    // Rows the stream will not read again (it reads the row above a strip to filter it).
    int rows_read() const { return rows_read_; }
    bool done() const { return next_strip_ == strips_.size(); }
    // The file once done(): signature and header chunks, one IDAT chunk a strip, IEND.
    std::vector<std::span<const uint8_t>> pieces() const;
    size_t bytes() const;
    size_t row_bytes() const { return row_bytes_; }

private:
    int width_, height_, channels_, bits_, level_;
    size_t row_bytes_;
    int strip_rows_;
    std::vector<uint8_t> head_, tail_;
    std::vector<std::vector<uint8_t>> strips_;  // each an IDAT chunk
    std::vector<uint32_t> adler_;               // adler32 of each strip's filtered bytes
    size_t next_strip_ = 0;
    int rows_read_ = 0;
};

}  // namespace specbake::io
