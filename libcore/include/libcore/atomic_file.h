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

// Throws OutputError("<path>: cannot create file (<reason>)") unless a file can be created beside
// `path` (its folder exists and is writable): checked before a long run, so that a mistyped
// output folder is reported at once rather than after minutes of work. Leaves nothing behind.
void check_can_write(const std::filesystem::path& path);

}  // namespace quadify::core
