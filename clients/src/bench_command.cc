// chasles bench: benchmark planner configurations through the Benchmark RPC.
#include <iostream>

#include "commands.h"

namespace chasles::cli {

int BenchCommand(const std::string& server, double timeout, const std::vector<std::string>& args) {
  std::cerr << "chasles: bench is not built yet\n";
  return 2;
}

}  // namespace chasles::cli
