#pragma once
/// \file
/// Commands of the chasles CLI that live in their own files and parse their own options.

#include <string>
#include <vector>

#include "connection.h"

namespace chasles::cli {

/// `chasles bench CONFIG.yaml [...]` (bench_command.cc) on the server `connection` names.
/// Returns the process exit code.
int BenchCommand(const ConnectionOptions& connection, double timeout, const std::vector<std::string>& args);

/// `chasles import-moveit SCENE.yaml REQUEST.yaml [...]` (import_moveit_command.cc). Returns the
/// process exit code: 0 printed, 1 the YAML does not convert (message names file, key and rule),
/// 2 bad arguments or unreadable files.
int ImportMoveItCommand(const std::vector<std::string>& args);

}  // namespace chasles::cli
