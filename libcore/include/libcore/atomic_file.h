// Atomic file writes: content goes to a temporary file in the target folder, then rename(2).
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace quadify::core {

// Calls `write` with a binary stream on a temp file beside `path`, flushes, checks the stream and
// renames it onto `path`. On any failure (including an exception from `write`) the temp file is
// removed and OutputError("<path>: <problem>") is thrown; `path` is untouched.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

// Several files that belong together (e.g. .gltf + .bin): all temps are written first, then all
// renamed; if any write fails, none of the targets is created or changed.
struct AtomicFilePart {
  std::filesystem::path path;
  std::function<void(std::ostream&)> write;
};
void write_files_atomically(const std::vector<AtomicFilePart>& parts);

}  // namespace quadify::core
