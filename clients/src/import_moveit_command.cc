// chasles import-moveit: MoveIt PlanningScene + MotionPlanRequest YAML -> chasles.v1.PlanRequest JSON.
#include <iostream>

#include "commands.h"

namespace chasles::cli {

int ImportMoveItCommand(const std::vector<std::string>& args) {
  std::cerr << "chasles: import-moveit is not built yet\n";
  return 2;
}

}  // namespace chasles::cli
