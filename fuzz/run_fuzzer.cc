// libFuzzer target: the offline run-file parser (design/run_file.h ParseRun) on arbitrary
// text, scenes resolved in scenes/ so mutated example runs load their real scenes. Errors must
// be RunError naming the file, the JSON pointer and the problem.

#include <cstddef>
#include <cstdint>
#include <string>

#include "design/run_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)tangent::design::ParseRun(text, "fuzz.run.json", TANGENT_SCENES_DIR);
  } catch (const tangent::design::RunError&) {
  }
  return 0;
}
