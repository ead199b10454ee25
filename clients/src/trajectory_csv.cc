#include "trajectory_csv.h"

#include <iomanip>

namespace chasles {

void WriteTrajectoryCsv(const v1::JointTrajectory& trajectory, std::ostream& out) {
  out << "t";
  for (const char* prefix : {"q_", "qd_", "qdd_"}) {
    for (const std::string& name : trajectory.joint_names()) out << ',' << prefix << name;
  }
  out << '\n' << std::setprecision(17);
  const int n = trajectory.joint_names_size();
  auto write = [&](const google::protobuf::RepeatedField<double>& values) {
    for (int i = 0; i < n; ++i) {
      out << ',';
      if (i < values.size()) out << values[i];
    }
  };
  for (const v1::TrajectoryPoint& point : trajectory.points()) {
    out << point.time_from_start();
    write(point.positions());
    write(point.velocities());
    write(point.accelerations());
    out << '\n';
  }
}

}  // namespace chasles
