// libFuzzer entry point of fuzz/targets.hpp's method_file_one (built by scripts/fuzz.sh).
#include "fuzz/targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  stiffbench::fuzz::method_file_one(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
