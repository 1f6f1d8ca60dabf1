// A zlib deflate state that a thread keeps from one piece of an image to the next (the PNG
// encoder's bands, the EXR encoder's blocks). A fresh z_stream allocates and clears about
// 260 kB; made afresh for each band, it was a third of the encoding of hw1 simple.xml's image.
#pragma once

#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace prism::detail {

class DeflateStream {
public:
    // `window_bits` as deflateInit2 takes it: 15 for a zlib stream (header and Adler-32, as
    // OpenEXR's blocks are), -15 for raw deflate (the PNG bands, joined behind one header).
    DeflateStream(int level, int window_bits) {
        ready_ = deflateInit2(&stream_, level, Z_DEFLATED, window_bits, 8, Z_DEFAULT_STRATEGY) == Z_OK;
    }
    ~DeflateStream() {
        if (ready_) deflateEnd(&stream_);
    }
    DeflateStream(const DeflateStream&) = delete;
    DeflateStream& operator=(const DeflateStream&) = delete;

    // The state reset for a new stream, or null if zlib could not make or reset it.
    z_stream* reset() { return ready_ && deflateReset(&stream_) == Z_OK ? &stream_ : nullptr; }

    // Deflates `size` bytes at `input` into `output` (resized to what was written) with `flush`
    // (Z_FINISH ends the stream; Z_SYNC_FLUSH ends a band that another continues). False if zlib
    // failed or the output did not fit (the bound covers a finished stream; a sync flush adds
    // at most an empty stored block).
    bool deflate_all(const std::uint8_t* input, std::size_t size, int flush, std::vector<std::uint8_t>& output) {
        z_stream* stream = reset();
        if (!stream) return false;
        output.resize(deflateBound(stream, uLong(size)) + 16);
        stream->next_in = const_cast<std::uint8_t*>(input);
        stream->avail_in = uInt(size);
        stream->next_out = output.data();
        stream->avail_out = uInt(output.size());
        const int result = ::deflate(stream, flush);
        const bool ok = flush == Z_FINISH ? result == Z_STREAM_END
                                          : (result == Z_OK && stream->avail_in == 0 && stream->avail_out > 0);
        output.resize(output.size() - stream->avail_out);
        return ok;
    }

private:
    z_stream stream_{};
    bool ready_ = false;
};

}  // namespace prism::detail
