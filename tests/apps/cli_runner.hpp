// The alloy command line run in-process, as a user would type it, for the
// tests of its commands (alloy_cli_test, save_file_test, plugins_test): the
// exit code and what it printed on each stream.
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "apps/alloy/commands.hpp"

namespace alloy::app::cli_test {

struct Result {
  int code;
  std::string out, err;
};

/// `alloy ARGS...`.
inline Result cli(std::vector<std::string> args) {
  args.insert(args.begin(), "alloy");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  std::ostringstream out, err;
  const int code = run_cli(int(argv.size()), argv.data(), out, err);
  return {code, out.str(), err.str()};
}

}  // namespace alloy::app::cli_test
