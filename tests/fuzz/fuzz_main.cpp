// One libFuzzer binary per target: this file is compiled once per target with
// ALLOY_FUZZ_ENTRY naming the entry of fuzz_entries.hpp it drives.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_entries.hpp"

#ifndef ALLOY_FUZZ_ENTRY
#error "ALLOY_FUZZ_ENTRY must name an entry of tests/fuzz/fuzz_entries.hpp"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  alloy::fuzz::ALLOY_FUZZ_ENTRY(data, size);
  return 0;
}
