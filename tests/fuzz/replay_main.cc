// The driver of the harnesses in a build without libFuzzer (GCC, the Release test build CI runs):
// each harness's seeds, then deterministic mutations of them (bytes flipped, set, cut, repeated,
// inserted) for a few seconds. No coverage guidance and no sanitizer, so this is no campaign
// (scripts/fuzz is); it fails when a harness no longer builds, or when an input near a seed breaks
// a reader's contract or crashes it.
//   <name>_fuzz SEED_DIR [SECONDS]
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

void Run(const std::string& bytes) {
  LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
}

std::string Mutate(std::string bytes, std::mt19937_64& random) {
  const auto at = [&](std::size_t n) { return n == 0 ? 0 : std::size_t(random() % n); };
  switch (random() % 6) {
    case 0:  // flip a bit
      if (!bytes.empty()) bytes[at(bytes.size())] ^= char(1 << (random() % 8));
      break;
    case 1:  // an interesting byte
      if (!bytes.empty()) bytes[at(bytes.size())] = "\x00\x01\x7f\x80\xff"[random() % 5];
      break;
    case 2:  // cut short
      bytes.resize(at(bytes.size() + 1));
      break;
    case 3: {  // repeat a chunk
      const std::size_t from = at(bytes.size()),
                        length = at(std::min<std::size_t>(bytes.size() - from, 64) + 1);
      bytes.insert(at(bytes.size() + 1), bytes.substr(from, length));
      break;
    }
    case 4:  // insert random bytes
      bytes.insert(at(bytes.size() + 1), std::string(1 + at(8), char(random())));
      break;
    default:  // a big-endian or little-endian extreme in four bytes
      if (bytes.size() >= 4) {
        const std::size_t i = at(bytes.size() - 3);
        for (int k = 0; k < 4; ++k) bytes[i + k] = random() % 2 ? '\xff' : '\x7f';
      }
  }
  return bytes;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s SEED_DIR [SECONDS]\n", argv[0]);
    return 2;
  }
  const double seconds = argc == 3 ? std::atof(argv[2]) : 2.0;
  std::vector<std::string> seeds;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(argv[1], error)) {
    std::ifstream in(entry.path(), std::ios::binary);
    seeds.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  if (error || seeds.empty()) {
    std::fprintf(stderr, "%s: no seeds in %s\n", argv[0], argv[1]);
    return 2;
  }
  for (const std::string& seed : seeds) Run(seed);
  std::mt19937_64 random(20261201);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  std::size_t runs = seeds.size();
  while (std::chrono::steady_clock::now() < end) {
    std::string input = seeds[random() % seeds.size()];
    for (int k = 1 + int(random() % 4); k > 0; --k) input = Mutate(std::move(input), random);
    Run(input);
    ++runs;
  }
  std::printf("%s: %zu inputs (%zu seeds), no crash and no broken contract\n", argv[0], runs, seeds.size());
  return 0;
}
