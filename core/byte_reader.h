#pragma once
// A bounds-checked cursor over the bytes of a file being parsed: every read
// checks what is left before touching memory, and running short is an
// IoError naming the file, the field and the byte offset. Little-endian
// fields (OpenVDB, OpenEXR) read as the host's on x86-64.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "core/error.h"

namespace terrain {

class ByteReader {
public:
    ByteReader(const std::string& file, std::string_view bytes) : file_(file), bytes_(bytes) {}

    std::size_t position() const { return pos_; }
    std::size_t remaining() const { return bytes_.size() - pos_; }
    std::size_t size() const { return bytes_.size(); }
    const std::string& file() const { return file_; }

    /// The next n bytes, consumed.
    std::string_view take(std::uint64_t n, const char* what) {
        need(n, what);
        const std::string_view out = bytes_.substr(pos_, static_cast<std::size_t>(n));
        pos_ += static_cast<std::size_t>(n);
        return out;
    }
    void skip(std::uint64_t n, const char* what) { take(n, what); }
    void seek(std::uint64_t position, const char* what) {
        if (position > bytes_.size())
            throw IoError(file_, std::string("corrupt or truncated: ") + what + " points past the end of the file");
        pos_ = static_cast<std::size_t>(position);
    }

    template <class T>
    T read(const char* what) {
        T value;
        std::memcpy(&value, take(sizeof(T), what).data(), sizeof(T));
        return value;
    }

    /// An OpenVDB string: int32 length, then the bytes; at most maxBytes.
    std::string_view sizedString(std::uint32_t maxBytes, const char* what) {
        const auto length = read<std::int32_t>(what);
        if (length < 0 || static_cast<std::uint32_t>(length) > maxBytes)
            throw IoError(file_, std::string("corrupt: ") + what + " declares " + std::to_string(length) +
                                     " bytes (at most " + std::to_string(maxBytes) + ")");
        return take(static_cast<std::uint32_t>(length), what);
    }

    /// A NUL-terminated string of at most maxBytes characters (OpenEXR).
    std::string_view cString(std::size_t maxBytes, const char* what) {
        const std::size_t end = bytes_.find('\0', pos_);
        if (end == std::string_view::npos || end - pos_ > maxBytes)
            throw IoError(file_, std::string("corrupt or truncated: ") + what +
                                     " is not a terminated name of at most " + std::to_string(maxBytes) + " bytes");
        const std::string_view out = bytes_.substr(pos_, end - pos_);
        pos_ = end + 1;
        return out;
    }

private:
    void need(std::uint64_t n, const char* what) const {
        if (n > remaining())
            throw IoError(file_, std::string("truncated: ") + what + " at byte " + std::to_string(pos_) + " needs " +
                                     std::to_string(n) + " bytes, " + std::to_string(remaining()) + " left");
    }

    std::string file_;
    std::string_view bytes_;
    std::size_t pos_ = 0;
};

}  // namespace terrain
