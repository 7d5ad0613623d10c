// Internal helpers shared by the mesh readers: error reporting, a bounded text cursor, number
// parsing and the final validation every reader runs. Not installed.
#pragma once

#include <libcore/mesh.h>
#include <libcore/read_mesh.h>
#include <libcore/status.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace quadify::core::detail {

// Throws InputError("<name>: <problem>").
[[noreturn]] inline void fail(const std::string& name, const std::string& problem) {
  throw InputError(name + ": " + problem);
}

// Checks an announced element count against the option cap and against what the remaining bytes
// can hold (each element needs at least `min_bytes_each` bytes), before anything is allocated.
inline void check_count(const std::string& name, long long count, long long min_bytes_each,
                        long long bytes_left, const ReadOptions& options, const char* what) {
  if (count < 0) fail(name, std::string("negative ") + what + " count " + std::to_string(count));
  if (count > options.max_elements)
    fail(name, std::string(what) + " count " + std::to_string(count) +
                   " exceeds the limit of " + std::to_string(options.max_elements));
  if (min_bytes_each > 0 && count > bytes_left / min_bytes_each)
    fail(name, std::string("file too short for ") + std::to_string(count) + " " + what +
                   " (truncated or corrupt header)");
}

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Splits a line into whitespace-separated tokens without allocating.
class Tokens {
 public:
  explicit Tokens(std::string_view line) : rest_(line) {}
  // Next token, empty at the end of the line.
  std::string_view next() {
    size_t i = 0;
    while (i < rest_.size() && is_space(rest_[i])) ++i;
    size_t j = i;
    while (j < rest_.size() && !is_space(rest_[j])) ++j;
    std::string_view tok = rest_.substr(i, j - i);
    rest_ = rest_.substr(j);
    return tok;
  }

 private:
  std::string_view rest_;
};

// Iterates over lines of a text buffer ('\n' or "\r\n"), counting line numbers from 1.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  bool next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    *line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++line_number_;
    return true;
  }
  int line_number() const { return line_number_; }
  long long bytes_left() const {
    return pos_ >= text_.size() ? 0 : static_cast<long long>(text_.size() - pos_);
  }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int line_number_ = 0;
};

inline bool parse_double(std::string_view tok, double* value) {
  if (tok.empty()) return false;
  if (tok.front() == '+') tok.remove_prefix(1);
  const char* end = tok.data() + tok.size();
  auto [ptr, ec] = std::from_chars(tok.data(), end, *value);
  // Out-of-range values (1e999) parse as errors; they would be infinite anyway.
  return ec == std::errc() && ptr == end;
}

inline bool parse_ll(std::string_view tok, long long* value) {
  if (tok.empty()) return false;
  if (tok.front() == '+') tok.remove_prefix(1);
  const char* end = tok.data() + tok.size();
  auto [ptr, ec] = std::from_chars(tok.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

inline std::string quoted(std::string_view tok) {
  constexpr size_t kMaxShown = 40;  // characters of a bad token repeated in a message
  std::string s(tok.substr(0, kMaxShown));
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return "'" + s + (tok.size() > kMaxShown ? "...'" : "'");
}

// Little-endian host check (binary PLY/STL/GLB are read byte by byte, so only used to decide
// whether to swap).
inline bool host_is_little_endian() {
  const uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// Final checks run by read_mesh_from_memory on every reader's output: finite coordinates,
// vertex/uv ids in range, at least one face. Messages name the first offending element.
void validate_read_mesh(const PolyMesh& mesh, const std::string& name);

// The readers. `bytes` is the whole file; `name` is used in messages.
PolyMesh read_obj(const std::string& bytes, const std::string& name, const ReadOptions& options);
PolyMesh read_off(const std::string& bytes, const std::string& name, const ReadOptions& options);
PolyMesh read_ply(const std::string& bytes, const std::string& name, const ReadOptions& options);
PolyMesh read_stl(const std::string& bytes, const std::string& name, const ReadOptions& options);
// `base_dir` resolves external buffer URIs of a .gltf (empty: only embedded data is allowed).
PolyMesh read_gltf(const std::string& bytes, bool binary, const std::string& name,
                   const std::string& base_dir, const ReadOptions& options);

}  // namespace quadify::core::detail
