// Deterministic mutation fuzzing of every reader: truncations, byte flips, number replacements
// and chunk duplications of small valid files. Each read must succeed or throw InputError —
// never crash, hang, run out of memory or throw anything else.
#include <libcore/read_mesh.h>
#include <libcore/status.h>

#include <gtest/gtest.h>

#include "read_mesh_samples.h"

#include <chrono>
#include <random>
#include <string>
#include <vector>

namespace quadify::core {
namespace {

using namespace test_samples;

constexpr int kMutationsPerSeed = 1000;   // × 9 seeds = 9000 reads
constexpr double kBudgetSeconds = 10.0;   // whole test, also under ASan

std::string mutate(const std::string& seed, std::mt19937& rng) {
  std::string s = seed;
  auto pick = [&](size_t n) { return n == 0 ? size_t(0) : std::uniform_int_distribution<size_t>(0, n - 1)(rng); };
  const int kind = std::uniform_int_distribution<int>(0, 4)(rng);
  if (kind == 0) {
    s.resize(pick(s.size() + 1));  // truncate
  } else if (kind == 1) {
    const int flips = 1 + static_cast<int>(pick(8));
    for (int i = 0; i < flips && !s.empty(); ++i) s[pick(s.size())] = static_cast<char>(pick(256));
  } else if (kind == 2) {
    // Replace a decimal number (or an arbitrary position) by a huge or negative one.
    static const char* kValues[] = {"4294967295", "-1", "999999999999", "-2147483648", "1e308",
                                    "nan", "-0", "2147483647", "0", "1e-320"};
    const std::string value = kValues[pick(10)];
    size_t pos = pick(s.size());
    while (pos < s.size() && !std::isdigit(static_cast<unsigned char>(s[pos]))) ++pos;
    size_t end = pos;
    while (end < s.size() && (std::isdigit(static_cast<unsigned char>(s[end])) || s[end] == '.')) ++end;
    s.replace(std::min(pos, s.size()), end - std::min(pos, s.size()), value);
  } else if (kind == 3) {
    // Overwrite 4 bytes with an extreme binary integer (counts, offsets, indices).
    static const uint32_t kWords[] = {0xffffffffu, 0x7fffffffu, 0x80000000u, 0x10000000u, 0u};
    const uint32_t w = kWords[pick(5)];
    if (s.size() >= 4) std::memcpy(s.data() + pick(s.size() - 3), &w, 4);
  } else {
    const size_t a = pick(s.size()), len = pick(std::min<size_t>(64, s.size() - a + 1));
    s.insert(pick(s.size() + 1), s.substr(a, len));  // duplicate a chunk
  }
  return s;
}

TEST(FuzzReaders, MutatedFilesEndInSuccessOrInputError) {
  struct Seed { std::string bytes; MeshFormat format; const char* name; };
  const std::vector<Seed> seeds = {
      {tet_obj(), MeshFormat::kObj, "fuzz.obj"},
      {tet_off(), MeshFormat::kOff, "fuzz.off"},
      {tet_ply_ascii(), MeshFormat::kPly, "fuzz_ascii.ply"},
      {tet_ply_binary(false), MeshFormat::kPly, "fuzz_le.ply"},
      {tet_ply_binary(true), MeshFormat::kPly, "fuzz_be.ply"},
      {tet_stl_ascii(), MeshFormat::kStl, "fuzz_ascii.stl"},
      {tet_stl_binary(), MeshFormat::kStl, "fuzz_bin.stl"},
      {tet_gltf(), MeshFormat::kGltf, "fuzz.gltf"},
      {tet_glb(), MeshFormat::kGlb, "fuzz.glb"},
  };
  ReadOptions options;
  options.max_elements = 1'000'000;  // mutated counts must be rejected, not allocated
  std::mt19937 rng(20240611u);
  const auto t0 = std::chrono::steady_clock::now();
  int n_ok = 0, n_error = 0;
  for (const Seed& seed : seeds) {
    int seed_ok = 0;
    for (int i = 0; i < kMutationsPerSeed; ++i) {
      const std::string bytes = mutate(seed.bytes, rng);
      try {
        const PolyMesh m = read_mesh_from_memory(bytes, seed.format, seed.name, options);
        EXPECT_GT(m.n_faces(), 0) << seed.name << " mutation " << i;
        ++n_ok, ++seed_ok;
      } catch (const InputError& e) {
        ++n_error;
        EXPECT_EQ(std::string(e.what()).rfind(seed.name, 0), 0u) << "message must start with the name: " << e.what();
      } catch (const std::exception& e) {
        ADD_FAILURE() << seed.name << " mutation " << i << ": unexpected exception " << e.what();
      }
    }
    // The unmutated seed itself must read.
    EXPECT_NO_THROW((void)read_mesh_from_memory(seed.bytes, seed.format, seed.name)) << seed.name;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(seconds, kBudgetSeconds) << n_ok << " ok, " << n_error << " errors";
  EXPECT_GT(n_error, 0);
  EXPECT_GT(n_ok, 0);
  RecordProperty("reads_ok", n_ok);
  RecordProperty("reads_error", n_error);
  std::printf("fuzz: %d ok, %d InputError, %.2f s\n", n_ok, n_error, seconds);
}

}  // namespace
}  // namespace quadify::core
