#include <libcore/atomic_file.h>
#include <libcore/status.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <exception>
#include <fstream>
#include <unistd.h>

namespace quadify::core {
namespace fs = std::filesystem;
namespace {

fs::path temp_path_for(const fs::path& target) {
  static std::atomic<unsigned> counter{0};  // unique names within one process
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  // Built with append: GCC 12 warns falsely (-Wrestrict) on `"." + std::string`.
  std::string name = ".";
  name.append(target.filename().string()).append(".tmp.").append(std::to_string(::getpid()));
  name.append(".").append(std::to_string(counter++));
  return dir / name;
}

// Creates (truncates) the temporary file tmp for target; OutputError naming target on failure.
std::ofstream open_temp(const fs::path& target, const fs::path& tmp) {
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw OutputError(target.string() + ": cannot create file (" + std::strerror(errno) + ")");
  return out;
}

void write_temp(const fs::path& target, const fs::path& tmp, const std::function<void(std::ostream&)>& write) {
  std::ofstream out = open_temp(target, tmp);
  try {
    write(out);
  } catch (const OutputError&) {
    throw;
  } catch (const std::exception& e) {  // the header promises OutputError for any failure
    throw OutputError(target.string() + ": " + e.what());
  }
  out.flush();
  if (!out) throw OutputError(target.string() + ": write failed (disk full or I/O error)");
  out.close();
  if (out.fail()) throw OutputError(target.string() + ": closing the file failed");
}

}  // namespace

void write_files_atomically(const std::vector<AtomicFilePart>& parts) {
  std::vector<fs::path> temps;
  try {
    for (const auto& part : parts) {
      temps.push_back(temp_path_for(part.path));
      write_temp(part.path, temps.back(), part.write);
    }
    for (size_t i = 0; i < parts.size(); ++i) {
      std::error_code ec;
      fs::rename(temps[i], parts[i].path, ec);
      if (ec) throw OutputError(parts[i].path.string() + ": cannot rename temporary file (" + ec.message() + ")");
    }
  } catch (...) {
    std::error_code ec;
    for (const auto& t : temps) fs::remove(t, ec);
    throw;
  }
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  write_files_atomically({AtomicFilePart{path, write}});
}

void check_can_write(const fs::path& path) {
  const fs::path tmp = temp_path_for(path);
  open_temp(path, tmp).close();
  std::error_code ec;
  fs::remove(tmp, ec);
}

}  // namespace quadify::core
