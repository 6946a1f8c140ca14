// libFuzzer target: any bytes given to the design parser either parse or are
// rejected with InputError. Any other exception, crash or sanitizer report is
// a bug.
#include <cstdint>
#include <string>

#include "fabatlas/design/design.h"
#include "fabatlas/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    fabatlas::design::Design d = fabatlas::design::ParseDesign(text, "fuzz.yaml");
    (void)d;
  } catch (const fabatlas::InputError&) {
  }
  return 0;
}
