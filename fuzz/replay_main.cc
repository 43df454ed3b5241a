// A main for the fuzz targets in builds without libFuzzer (gcc): runs every file named on the
// command line, or every regular file in a named folder, through LLVMFuzzerTestOneInput once.
// ctest runs each target this way over its seed corpus and its kept findings
// (fuzz/regressions/), so an input that once crashed stays a test.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

int RunFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "replay: cannot read %s\n", path.c_str());
    return 1;
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int inputs = 0, errors = 0;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path p(argv[i]);
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::directory_iterator(p)) {
        if (!e.is_regular_file()) continue;
        errors += RunFile(e.path());
        ++inputs;
      }
    } else {
      errors += RunFile(p);
      ++inputs;
    }
  }
  std::printf("replay: %d inputs, %d unreadable\n", inputs, errors);
  return errors == 0 && inputs > 0 ? 0 : 1;
}
