#pragma once
// Atomic file writes: every writer writes to a temporary name beside the
// target and renames it, so a failure never leaves a half-written file in
// place of a good one.
#include <string>

namespace terrain {

/// Writes bytes to `file` atomically (temporary file + rename).
void writeFileAtomic(const std::string& file, const std::string& bytes);

/// Returns a temporary name beside `file` for an atomic write.
std::string temporaryNameFor(const std::string& file);

/// Renames tmp onto file, removing tmp and throwing IoError on failure.
void commitTemporary(const std::string& tmp, const std::string& file);

}  // namespace terrain
